"use strict";

const KEY_STORAGE = "percussim.apiKey";
const POLL_MS = 250;
const FINISHED = ["succeeded", "failed", "cancelled"];
const RECENT = 12;
const $ = (id) => document.getElementById(id);

// An element with attributes and children; strings become text nodes, so nothing from the
// service is ever parsed as HTML.
function h(tag, attrs = {}, ...children) {
  const el = document.createElement(tag);
  for (const [name, value] of Object.entries(attrs)) {
    if (value === null || value === undefined || value === false) continue;
    if (name.startsWith("on")) el.addEventListener(name.slice(2), value);
    else el.setAttribute(name, value);
  }
  el.append(...children.flat(Infinity).filter((c) => c !== null && c !== undefined && c !== false));
  return el;
}

// `digits` significant digits: 484.0, 179.9, 12345, 0.9335; an exponent only below 0.001
// (4.682e-13) and from a million up (8.014e+11), where fixed decimals would run off the table
// or bury the digits that count.
function fmt(value, digits = 4) {
  if (typeof value !== "number" || !Number.isFinite(value)) return "—";
  if (value === 0) return "0";
  if (Math.abs(value) < 1e-3 || Math.abs(value) >= 1e6) return value.toExponential(digits - 1);
  const decimals = digits - 1 - Math.floor(Math.log10(Math.abs(value)));
  return value.toFixed(Math.max(decimals, 0));
}

// A number as typed, or the text itself when it is not one, for the service to name.
function typed(text) {
  const value = Number(text);
  return text !== "" && Number.isFinite(value) ? value : text;
}

const clock = (iso) => (iso ? new Date(iso).toLocaleTimeString("en-GB") : "");

function seconds(fromIso, toIso) {
  return fromIso && toIso ? (new Date(toIso) - new Date(fromIso)) / 1000 : null;
}

// ---------------------------------------------------------------------------------------------
// The API: every call carries the key, and a 401 anywhere asks the user for one.

class ApiError extends Error {
  constructor(status, detail, retryAfter) {
    super(typeof detail === "string" ? detail : `the service answered ${status}`);
    this.status = status;
    this.detail = detail;
    this.retryAfter = retryAfter;
  }
}

// `askKey: false`: a 401 is only thrown, not asked about (a check while the user types must not
// take the focus from the field).
async function api(path, { askKey = true, ...options } = {}) {
  const headers = new Headers(options.headers || {});
  const key = localStorage.getItem(KEY_STORAGE);
  if (key) headers.set("X-API-Key", key);
  const response = await fetch(path, { ...options, headers });
  if (response.ok) return response;
  const text = await response.text();
  let detail = text;
  try { detail = JSON.parse(text).detail ?? text; } catch { /* a plain-text answer */ }
  if (response.status === 401 && askKey) askForKey(detail);
  throw new ApiError(response.status, detail, response.headers.get("Retry-After"));
}

const getJSON = async (path, options) => (await api(path, options)).json();

function describe(error) {
  if (!(error instanceof ApiError)) return `the service could not be reached (${error.message})`;
  if (error.status === 401) return "an API key is needed";
  const retry = error.retryAfter ? ` Try again in ${error.retryAfter} s.` : "";
  return `${error.message}${retry}`;
}

// A blob fetched with the key, as an object URL: an <img> or a link cannot send the header.
async function objectUrl(path, urls) {
  const url = URL.createObjectURL(await (await api(path)).blob());
  urls.push(url);
  return url;
}

function askForKey(detail) {
  const banner = $("key-needed");
  const reason = typeof detail === "string" && detail ? detail : "this service needs an API key";
  banner.textContent = `${reason[0].toUpperCase()}${reason.slice(1)}: enter a key above and press Save.`;
  banner.hidden = false;
  $("api-key").classList.add("attention");
  $("api-key").focus();
}

function saveKey(event) {
  event.preventDefault();
  const key = $("api-key").value.trim();
  if (key) localStorage.setItem(KEY_STORAGE, key);
  else localStorage.removeItem(KEY_STORAGE);
  $("key-needed").hidden = true;
  $("api-key").classList.remove("attention");
  loadPresets();
  refreshJobs();
  if (shown) openJob(shown.id);
}

// ---------------------------------------------------------------------------------------------
// The case: a preset or pasted JSON, checked for syntax here and for meaning by the service.

async function loadPresets() {
  try {
    const presets = await getJSON("/v1/presets");
    $("preset").replaceChildren(h("option", { value: "" }, "— choose a preset —"),
      ...presets.map((p) => h("option", { value: p.name }, p.name)));
    showProblems($("case-errors"), null);
  } catch (error) {
    // A missing key has its own banner.
    if (error.status !== 401) showProblems($("case-errors"), `The presets could not be loaded: ${describe(error)}`);
  }
}

async function choosePreset() {
  const name = $("preset").value;
  if (!name) return;
  try {
    const preset = await getJSON(`/v1/presets/${encodeURIComponent(name)}`);
    $("preset-description").textContent = preset.description || "";
    // The description last: the physics is what one reads and edits.
    const { description, ...physics } = preset;
    setCaseText(JSON.stringify({ ...physics, description }, null, 2));
    showProblems($("case-errors"), null);
  } catch (error) {
    showProblems($("case-errors"), `Preset ${name} could not be loaded: ${describe(error)}`);
  }
}

// The case editor's text replaced whole (a preset, a fitted case): an "input" event, as when the
// user types, so that the form follows.
function setCaseText(text) {
  const area = $("case-json");
  area.value = text;
  area.dispatchEvent(new Event("input"));
}

// A box of problems under a form: a title, then a table of each field (or place) and its problem;
// `title` null empties and hides it.
function showProblems(box, title, problems = [], where = "field") {
  box.hidden = !title;
  box.replaceChildren();
  if (!title) return;
  box.append(h("p", { class: "title" }, title));
  if (problems.length) {
    box.append(h("table", { class: "problems" },
      h("thead", {}, h("tr", {}, h("th", {}, where), h("th", {}, "problem"))),
      h("tbody", {}, problems.map((p) =>
        h("tr", {}, h("td", { class: "field" }, p.field), h("td", { class: "message" }, p.message))))));
  }
}

// V8 names a syntax error's character position; the line and column are what a user can find.
function syntaxProblem(text, error) {
  const match = /position (\d+)/.exec(error.message);
  if (!match) return { field: "", message: error.message };
  const position = Number(match[1]);
  const before = text.slice(0, position).split("\n");
  const area = $("case-json");
  area.focus();
  area.setSelectionRange(position, position + 1);
  return { field: `line ${before.length}, column ${before.at(-1).length + 1}`,
           message: error.message.replace(/ in JSON at position \d+.*$/, "") };
}

// The case in the editor, parsed; null, with the reason shown in `box`, when there is none or it
// is not JSON.
function editedCase(box) {
  const text = $("case-json").value;
  if (!text.trim()) {
    showProblems(box, "Pick a preset or paste a case first.");
    return null;
  }
  try {
    return JSON.parse(text);
  } catch (error) {
    showProblems(box, "The case is not valid JSON, so it was not sent.", [syntaxProblem(text, error)], "where");
    return null;
  }
}

// POST `body` (JSON text) to `path` from the form whose submit button is `button`, then open what
// it made (`open`, a job by default); a refusal is shown in `box`, each field with its problem
// (`where` maps a field to where the user finds it), and handed to `refused`.
async function send(path, body, { button, box, what, where = (field) => field,
                                  open = (job) => openJob(job.id), refused = () => {} }) {
  button.disabled = true;
  try {
    const made = await getJSON(path, { method: "POST", headers: { "Content-Type": "application/json" }, body });
    showProblems(box, null);
    refused([]);
    open(made);
    refreshJobs();
  } catch (error) {
    if (Array.isArray(error.detail)) {
      const n = error.detail.length;
      showProblems(box, `The service refused the ${what}: ${n} problem${n === 1 ? "" : "s"}.`,
                   error.detail.map((d) => ({ ...d, field: where(d.field) })));
      refused(error.detail);
    } else {
      showProblems(box, `The ${what} was not submitted: ${describe(error)}`);
    }
  } finally {
    button.disabled = false;
  }
}

async function submitCase(event) {
  event.preventDefault();
  const box = $("case-errors");
  // The text as typed: the service reads it and names what is wrong.
  if (editedCase(box)) {
    await send("/v1/jobs", $("case-json").value, { button: $("submit"), box, what: "case", refused: showFieldProblems });
  }
}

// ---------------------------------------------------------------------------------------------
// Recent jobs, each finished run with a box to pick it for a comparison.

const COMPARE_MIN = 2;
const COMPARE_MAX = 8;
const picked = new Set(); // the jobs ticked for a comparison, kept across refreshes

function pickBox(job) {
  if (job.status !== "succeeded" || isStudy(job)) return h("span", { class: "pick" });
  return h("input", { type: "checkbox", class: "pick", "data-pick": job.id, checked: picked.has(job.id),
                      "aria-label": `compare ${job.name || job.id}`,
                      onchange: (event) => { event.target.checked ? picked.add(job.id) : picked.delete(job.id); pickedChanged(); } });
}

function pickedChanged() {
  const n = picked.size;
  $("compare").disabled = n < COMPARE_MIN || n > COMPARE_MAX;
  $("compare").textContent = n ? `Compare ${n}` : "Compare";
  $("compare-hint").textContent = n > COMPARE_MAX ? `at most ${COMPARE_MAX} jobs: untick ${n - COMPARE_MAX}`
    : n < COMPARE_MIN ? `tick ${COMPARE_MIN} to ${COMPARE_MAX} finished jobs to compare them` : "";
}

async function refreshJobs() {
  try {
    const { jobs } = await getJSON(`/v1/jobs?limit=${RECENT}`);
    $("jobs").replaceChildren(...jobs.map((job) => h("li", {},
      pickBox(job),
      h("button", { type: "button", class: "job-link", "data-job": job.id,
                    "aria-current": shown && shown.id === job.id ? "true" : null,
                    onclick: () => openJob(job.id) },
        h("span", { class: "job-name" }, job.name || "(unnamed)",
          job.kind && job.kind !== "run" ? h("span", { class: "kind" }, job.kind) : null,
          job.sweep ? h("span", { class: "kind" }, "sweep") : null),
        h("span", { class: `badge ${job.status}` }, job.status),
        h("span", { class: "muted small" }, clock(job.created))))));
    if (!jobs.length) $("jobs").replaceChildren(h("li", { class: "muted" }, "none yet"));
  } catch (error) {
    $("jobs").replaceChildren(h("li", { class: "muted" }, describe(error)));
  }
}

// ---------------------------------------------------------------------------------------------
// One job: polled until it finishes, then its summary, plots and result.

let shown = null; // the job on view: {id, timer, urls}; replaced whole when another is opened

// The right-hand panel shows one view: a job, a comparison or a sweep; `hash` links to it.
const VIEWS = ["job", "comparison", "sweep-view"];

function showView(name, hash) {
  if (name !== "job") closeJob();
  history.replaceState(null, "", hash);
  $("no-job").hidden = true;
  for (const view of VIEWS) $(view).hidden = view !== name;
  // One column: the view is above the form (page.css), but the form's Run button is far below it.
  if (matchMedia("(max-width: 900px)").matches) $("job-panel").scrollIntoView({ block: "start" });
}

function closeJob() {
  if (!shown) return;
  clearTimeout(shown.timer);
  shown.urls.forEach((url) => URL.revokeObjectURL(url));
  shown = null;
}

function openJob(id) {
  closeJob();
  shown = { id, timer: null, urls: [] };
  showView("job", `#job=${id}`);
  document.querySelectorAll(".job-link").forEach((b) =>
    b.toggleAttribute("aria-current", b.dataset.job === id));
  $("job-title").textContent = id;
  $("job-error").hidden = true;
  $("summary").replaceChildren();
  $("study").replaceChildren();
  $("plots").replaceChildren();
  poll(shown);
}

async function poll(view) {
  let job;
  try {
    job = await getJSON(`/v1/jobs/${view.id}`);
  } catch (error) {
    if (view !== shown) return;
    showJobError(describe(error));
    // A lost connection may come back (an API restart); a missing job or key will not.
    if (!(error instanceof ApiError) || error.status >= 500) view.timer = setTimeout(() => poll(view), 4 * POLL_MS);
    return;
  }
  if (view !== shown) return;
  renderJob(job);
  if (!FINISHED.includes(job.status)) {
    view.timer = setTimeout(() => poll(view), POLL_MS);
    return;
  }
  refreshJobs();
  if (job.status === "failed") showJobError(job.error || "the job failed without a reason");
  if (job.status === "succeeded" && isStudy(job)) {
    await showStudy(view, job.kind);
  } else if (job.status === "succeeded") {
    const summary = await showSummary(view);
    if (summary) await showCharts(view, summary);
  }
}

function renderJob(job) {
  $("job-error").hidden = true;
  $("job-title").replaceChildren(job.name || "(unnamed)", h("span", { class: "muted small id" }, job.id));
  const status = $("job-status");
  status.textContent = job.status;
  status.className = `badge ${job.status}`;
  const percent = Math.round(job.progress * 100);
  const bar = $("progress-bar");
  bar.style.width = `${percent}%`;
  bar.className = job.status;
  bar.textContent = `${percent}%`;
  $("cancel").hidden = FINISHED.includes(job.status);
  $("edit-case").hidden = isStudy(job);
  $("download").hidden = job.status !== "succeeded" || isStudy(job);
  const ran = seconds(job.started, job.finished);
  $("job-times").textContent = [
    `submitted ${clock(job.created)}`,
    job.started && `started ${clock(job.started)}`,
    job.finished && `finished ${clock(job.finished)}`,
    ran !== null && (ran < 1 ? `ran ${+(ran * 1e3).toPrecision(3)} ms` : `ran ${+ran.toPrecision(3)} s`),
    job.worker && `on ${job.worker}`,
  ].filter(Boolean).join(" · ");
}

// A calibration or an optimisation: a job whose answer is not a run's result.
const isStudy = (job) => Boolean(job.kind) && job.kind !== "run";

function showJobError(message) {
  const box = $("job-error");
  box.textContent = message;
  box.hidden = false;
}

async function cancelJob() {
  try {
    // POST …/cancel, not DELETE: a job that finished meanwhile is kept, not removed.
    await api(`/v1/jobs/${shown.id}/cancel`, { method: "POST" });
  } catch (error) {
    // 409: it finished meanwhile, which the next poll shows.
    if (error.status !== 409) showJobError(`Cancel failed: ${describe(error)}`);
  }
}

// A case (a job's, a fitted or best one) into the form and the JSON view, to change and run again.
function loadCase(caseJson) {
  setCaseText(JSON.stringify(caseJson, null, 2));
  $("case-fields").scrollIntoView({ block: "start" });
}

async function editCase() {
  try {
    loadCase(await getJSON(`/v1/jobs/${shown.id}/case`));
  } catch (error) {
    showJobError(`The case could not be loaded: ${describe(error)}`);
  }
}

// Hand `blob` to the browser as a download named `name`.
function save(blob, name) {
  const url = URL.createObjectURL(blob);
  const link = h("a", { href: url, download: name });
  document.body.append(link);
  link.click();
  link.remove();
  setTimeout(() => URL.revokeObjectURL(url), 60_000); // once the browser has taken the file
}

// A file fetched with the key, named as the service names it (or `fallback`).
async function download(path, fallback) {
  const response = await api(path);
  const disposition = response.headers.get("Content-Disposition") || "";
  const match = /filename\*=utf-8''([^;]+)/i.exec(disposition) || /filename="?([^";]+)"?/i.exec(disposition);
  return { blob: await response.blob(), name: match ? decodeURIComponent(match[1]) : fallback };
}

async function downloadResult() {
  const button = $("download");
  button.disabled = true;
  button.textContent = "Downloading…";
  try {
    const { blob, name } = await download(`/v1/jobs/${shown.id}/result.h5`, `${shown.id}.h5`);
    save(blob, name);
  } catch (error) {
    showJobError(`The HDF5 result could not be downloaded: ${describe(error)}`);
  } finally {
    button.disabled = false;
    button.textContent = "Download HDF5";
  }
}

// ---------------------------------------------------------------------------------------------
// The pulse summary in engineers' units.

const us = (t) => fmt(t * 1e6);
const mm = (x) => fmt(x * 1e3);

function table(className, head, rows) {
  return h("table", { class: className },
    h("thead", {}, h("tr", {}, head.map((cell) => h("th", {}, cell)))),
    h("tbody", {}, rows));
}

function card(title, ...content) {
  return h("section", { class: "card" }, h("h3", {}, title), ...content);
}

// A quantity's estimated relative error, or why it has none (on hover).
function errorCell(s, quantity) {
  const estimate = (s.error_estimate || {})[quantity];
  if (estimate !== undefined) {
    const over = estimate > (s.tolerance ?? 0.01);
    return h("td", { class: over ? "num error over" : "num error" }, `±${fmt(100 * estimate, 2)}%`);
  }
  const reason = (s.not_estimated || {})[quantity];
  return h("td", { class: "num error muted", title: reason || "" }, reason ? "n/a" : "");
}

// A row of the pulse table; `quantity` names the summary's key, for whoever reads the page by machine.
function pulseRow(s, label, quantity, value, unit, x = "", t = "") {
  return h("tr", { "data-quantity": quantity },
    h("th", {}, label), h("td", { class: "num value" }, value), h("td", { class: "unit" }, unit),
    errorCell(s, quantity), h("td", { class: "num" }, x), h("td", { class: "num" }, t));
}

// An extreme's place and time: x (mm) and t (µs), blank without one.
const placed = (extreme) => (extreme ? [fmt(extreme.x * 1e3), us(extreme.time)] : ["", ""]);

// The pulse's headline quantities, as the pulse table and a comparison show them: `quantity` is the
// summary's name (its error estimate's too), `read` its SI value, `toUnit` that value in `unit`,
// `where` its place and time in the pulse table; an `optional` one is listed only when the case
// has it (a penetration needs a medium).
const PULSE = [
  { label: "Co-impact time", quantity: "co_impact_time", unit: "µs", read: (s) => s.co_impact_time, toUnit: (v) => v * 1e6 },
  { label: "Peak contact force", quantity: "peak_contact_force", unit: "kN", read: (s) => s.peak_contact_force?.value,
    toUnit: (v) => v / 1e3, where: (s) => ["", us(s.peak_contact_force.time)] },
  { label: "Max compressive stress", quantity: "max_compressive_stress", unit: "MPa", read: (s) => s.max_compressive_stress?.value,
    toUnit: (v) => v / 1e6, where: (s) => placed(s.max_compressive_stress) },
  { label: "Max tensile stress", quantity: "max_tensile_stress", unit: "MPa", read: (s) => s.max_tensile_stress?.value,
    toUnit: (v) => v / 1e6, where: (s) => placed(s.max_tensile_stress) },
  { label: "Striker rebound velocity", quantity: "striker_rebound_velocity", unit: "m/s", read: (s) => s.striker_rebound_velocity,
    toUnit: (v) => v, where: (s) => ["", s.contacts?.length ? us(s.contacts[0].end) : ""] },
  { label: "Energy to the medium", quantity: "energy.to_medium", unit: "J", read: (s) => s.energy?.to_medium, toUnit: (v) => v },
  { label: "Transfer efficiency", quantity: "energy.transfer_efficiency", unit: "%", read: (s) => s.energy?.transfer_efficiency,
    toUnit: (v) => 100 * v },
  { label: "Deepest penetration", quantity: "medium_penetration.max", unit: "mm", read: (s) => s.medium_penetration?.max,
    toUnit: (v) => v * 1e3, optional: true },
  { label: "Permanent penetration", quantity: "medium_penetration.permanent", unit: "mm",
    read: (s) => s.medium_penetration?.permanent, toUnit: (v) => v * 1e3, optional: true },
];

// A pulse quantity's value in its unit, or null when the summary has none.
function pulseValue({ read, toUnit }, s) {
  const value = read(s);
  return typeof value === "number" ? toUnit(value) : null;
}

function pulseCard(s) {
  const contacts = s.contacts || [];
  return card("Pulse",
    table("pulse", ["", "value", "unit", "error (est.)", "at x (mm)", "at t (µs)"], [
      PULSE.filter((q) => !q.optional || pulseValue(q, s) !== null).map((q) =>
        pulseRow(s, q.label, q.quantity, fmt(pulseValue(q, s)), q.unit, ...(q.where ? q.where(s) : []))),
      pulseRow(s, "Contacts", "contacts_total", String(s.contacts_total ?? contacts.length), ""),
    ]),
    contacts.length > 1 && h("details", {},
      h("summary", {}, `All ${contacts.length} contact intervals`),
      table("contacts", ["#", "start (µs)", "end (µs)", "duration (µs)"], contacts.map((c, i) =>
        h("tr", {}, h("td", { class: "num" }, String(i + 1)), h("td", { class: "num" }, us(c.start)),
          h("td", { class: "num" }, us(c.end)), h("td", { class: "num" }, us(c.end - c.start)))))));
}

// The terms the input ends as; those marked `rare` belong to some models only (an elastic
// striker, an anvil, a medium that yields, blows) and are listed when they are not 0.
const ENERGY_TERMS = [
  ["striker_kinetic", "Striker, kinetic"],
  ["striker_strain", "Striker, strain", "rare"],
  ["anvil_kinetic", "Anvil, kinetic", "rare"],
  ["tool_kinetic", "Tool, kinetic"],
  ["tool_strain", "Tool, strain"],
  ["contact_potential", "Contact, potential"],
  ["medium_potential", "Medium, potential"],
  ["medium_plastic", "Medium, plastic", "rare"],
  ["dissipated_contact", "Dissipated in the contact"],
  ["dissipated_medium", "Dissipated in the medium"],
  ["striker_withdrawn", "Withdrawn with the striker", "rare"],
  ["numerical", "Lost by the scheme"],
];

function energyCard(e) {
  const input = e.initial + e.external_work;
  const share = (value) => (input ? ((100 * value) / input).toFixed(1) : "—");
  const row = (label, key, value, className = null) => h("tr", { "data-energy": key, class: className },
    h("th", {}, label), h("td", { class: "num value" }, fmt(value)), h("td", { class: "num" }, share(value)));
  const residual = input - ENERGY_TERMS.reduce((sum, [key]) => sum + (e[key] ?? 0), 0);
  const tiny = Math.abs(residual) < 1e-9 * Math.max(Math.abs(input), 1);
  return card("Energy audit",
    table("energy", ["", "J", "% of input"], [
      row("Striker at impact", "initial", e.initial),
      row("External force's work", "external_work", e.external_work),
      row("Input", "input", input, "total"),
      row("To the medium", "to_medium", e.to_medium, "highlight"),
      h("tr", { class: "group" }, h("th", { colspan: 3 }, "At the end of the run")),
      ENERGY_TERMS.filter(([key, , rare]) => !rare || e[key]).map(([key, label]) => row(label, key, e[key])),
      h("tr", { class: "total" }, h("th", {}, "Balance (input − terms)"),
        h("td", { class: "num" }, tiny ? "0" : fmt(residual)), h("td", { class: "num" }, tiny ? "0" : share(residual))),
      h("tr", {}, h("th", {}, "Largest energy created"), h("td", {}),
        h("td", { class: "num" }, fmt(100 * e.max_excess_fraction, 3))),
    ]));
}

// The summary's blows table, a row a blow.
function blowsCard(blows) {
  const cell = (value) => h("td", { class: "num" }, value);
  return card(`Blows (${blows.length})`,
    table("blows", ["blow", "peak contact force (kN)", "max compressive stress (MPa)", "to the medium (J)",
                    "transfer efficiency (%)", "permanent penetration (mm)", "set (mm)"],
      blows.map((b, i) => h("tr", { "data-blow": i + 1 },
        h("th", {}, String(i + 1)), cell(fmt(b.peak_contact_force / 1e3)), cell(fmt(b.max_compressive_stress / 1e6)),
        cell(fmt(b.to_medium)), cell(fmt(100 * b.transfer_efficiency)), cell(mm(b.permanent_penetration)),
        cell(mm(b.set))))));
}

function modelCard(s) {
  const n = s.numerics || {};
  const pair = (label, value) => h("tr", {}, h("th", {}, label), h("td", { class: "num" }, value));
  const rows = [
    pair("Model", s.model), pair("Scheme", s.scheme), pair("Cells", n.cells ?? "—"),
    pair("Time step (µs)", us(n.time_step)), pair("Steps", n.steps ?? "—"),
    n.scheme === "paper" && pair("γ", fmt(n.gamma, 3)), n.scheme === "sigma" && pair("σ", fmt(n.sigma, 3)),
    pair("Courant number", fmt(n.courant, 3)),
  ];
  if (s.tolerance !== null && s.tolerance !== undefined) rows.push(pair("Tolerance", String(s.tolerance)));
  if (s.error_estimate) {
    rows.push(pair("Estimated error (worst)", `${fmt(100 * s.error_estimate.worst, 2)}%`),
      pair("Grids run", (s.runs || []).map((r) => r.cells).join(", ")));
  }
  return card("Model and numerics", h("table", { class: "model" }, h("tbody", {}, rows)),
    h("p", { class: "why" }, h("strong", {}, "Why: "), s.why || "—"));
}

function warningsBanner(warnings) {
  return warnings.length
    ? h("div", { class: "banner warning" }, h("p", { class: "title" },
        `${warnings.length} warning${warnings.length === 1 ? "" : "s"}`), h("ul", {}, warnings.map((w) => h("li", {}, w))))
    : h("p", { class: "muted small" }, "No warnings.");
}

async function showSummary(view) {
  let s;
  try {
    s = await getJSON(`/v1/jobs/${view.id}/summary`);
  } catch (error) {
    if (view === shown) showJobError(`The summary could not be loaded: ${describe(error)}`);
    return null;
  }
  if (view !== shown) return null;
  $("summary").replaceChildren(...[
    warningsBanner(s.warnings || []),
    pulseCard(s),
    s.blows && s.blows.length ? blowsCard(s.blows) : null, // null: a case without blows
    h("div", { class: "pair" }, energyCard(s.energy), modelCard(s)),
  ].filter(Boolean));
  return s;
}

// ---------------------------------------------------------------------------------------------
// A study's plot, drawn by the service: its PNG, a click opens the SVG full size.

// The plot's PNG in `frame`, fetched with the key; a click enlarges it.
async function showImage(frame, plot, view) {
  try {
    const img = h("img", { src: await objectUrl(plot.links.png, view.urls), alt: plot.title || plot.name,
                           title: "click to enlarge", onclick: () => enlarge(plot, view) });
    frame.replaceChildren(img);
  } catch (error) {
    frame.textContent = describe(error);
    frame.classList.add("unavailable");
  }
  frame.classList.remove("loading");
}

async function enlarge(plot, view) {
  const box = $("lightbox");
  const img = box.querySelector("img");
  try {
    const links = plot.chosen || plot.links;  // the times last chosen, if any
    img.src = await objectUrl(links.svg || links.png, view.urls);
  } catch (error) {
    showJobError(`The plot could not be opened: ${describe(error)}`);
    return;
  }
  img.alt = plot.title || plot.name;
  box.querySelector("figcaption").textContent = `${plot.title || plot.name} — click or press Esc to close`;
  box.hidden = false;
}

// ---------------------------------------------------------------------------------------------

document.addEventListener("DOMContentLoaded", () => {
  history.scrollRestoration = "manual"; // the view linked decides where the page is
  $("api-key").value = localStorage.getItem(KEY_STORAGE) || "";
  $("key-form").addEventListener("submit", saveKey);
  $("preset").addEventListener("change", choosePreset);
  $("case-form").addEventListener("submit", submitCase);
  $("refresh-jobs").addEventListener("click", refreshJobs);
  $("compare").addEventListener("click", () => openComparison([...picked]));
  $("cancel").addEventListener("click", cancelJob);
  $("edit-case").addEventListener("click", editCase);
  $("download").addEventListener("click", downloadResult);
  $("lightbox").addEventListener("click", () => { $("lightbox").hidden = true; });
  document.addEventListener("keydown", (event) => {
    if (event.key === "Escape") $("lightbox").hidden = true;
  });
  loadPresets();
  refreshJobs();
  const [, view, target] = /^#(job|compare|sweep)=([\w,-]+)$/.exec(location.hash) || [];
  if (view === "job") openJob(target);
  if (view === "compare") openComparison(target.split(","));
  if (view === "sweep") openSweep(target);
});
