// Sweeps on the page: the form that starts one over the case in the editor, and the sweep's view
// (its progress, a sortable table a row per variant, a summary quantity against a swept field).
import { api, describe } from "./api.js";
import { axisTitle, chartFigure, csvText, drawChart, PALETTE, plain } from "./charts.js";
import { $, card, fmt, h, typed } from "./dom.js";
import { editedCase, send } from "./editor.js";
import { openJob } from "./job.js";
import { refreshJobs } from "./jobs.js";
import { poll } from "./poll.js";
import { shown, shownUnit } from "./units.js";
import { showView } from "./view.js";

const SWEEP_POLL_MS = 500;
const SWEEP_START = [["striker.velocity", "5, 7.5, 10"]];

// The table's columns (the API's names) as [label, quantity]; a count has none.
const SWEEP_COLUMNS = {
  co_impact_time: ["Co-impact time", "time"],
  peak_contact_force: ["Peak contact force", "force"],
  max_compressive_stress: ["Max compressive stress", "stress"],
  max_tensile_stress: ["Max tensile stress", "stress"],
  striker_rebound_velocity: ["Rebound velocity", "speed"],
  energy_to_medium: ["Energy to the medium", "energy"],
  transfer_efficiency: ["Transfer efficiency", "ratio"],
  max_penetration: ["Deepest penetration", "length"],
  permanent_penetration: ["Permanent penetration", "length"],
  last_blow_set: ["Set of the last blow", "length"],
  contacts: ["Contacts", null],
  frequency: ["Blows a second", "rate"],
  impact_power: ["Impact power", "power"],
  hydraulic_efficiency: ["Efficiency from the supply", "ratio"],
  estimated_error: ["Estimated error", "ratio"],
  warnings: ["Warnings", null],
};
const columnUnit = (column) => (SWEEP_COLUMNS[column][1] ? shownUnit(SWEEP_COLUMNS[column][1]) : "");
// A column's value in its unit.
const columnValue = (column, value) => (SWEEP_COLUMNS[column][1] ? shown(value, SWEEP_COLUMNS[column][1]) : value);

// ---------------------------------------------------------------------------------------------
// The form: a row per field, its values as a list or as from:to:count.

function addSweepRow([path, values] = ["", ""]) {
  const input = (value, label, className, list) =>
    h("input", { value, class: className, list, spellcheck: "false", "aria-label": label, oninput: countVariants });
  const row = h("tr", {},
    h("td", {}, input(path, "field", "path", "fields")),
    h("td", {}, input(values, "values", "values"), h("span", { class: "row-problem", role: "alert" })),
    h("td", {}, h("button", { type: "button", class: "link remove", "aria-label": "remove this field",
                              title: "remove this field", onclick: () => { row.remove(); countVariants(); } }, "✕")));
  $("sweep-parameters").tBodies[0].append(row);
  countVariants();
  return row;
}

// `3, 5, 7` as [3, 5, 7]; `0.1:0.6:6` as six values from 0.1 to 0.6, to 12 digits so that a step
// of 0.1 gives 0.3, not 0.30000000000000004. Text that is not a number is passed on for the
// service to name.
export function sweepValues(text) {
  const range = /^\s*([^:]+):([^:]+):\s*(\d+)\s*$/.exec(text);
  if (range) {
    const [from, to, count] = [Number(range[1]), Number(range[2]), Number(range[3])];
    if (Number.isFinite(from) && Number.isFinite(to) && count >= 2) {
      return Array.from({ length: count }, (_, i) => Number((from + ((to - from) * i) / (count - 1)).toPrecision(12)));
    }
  }
  return text.split(/[\s,;]+/).filter(Boolean).map(typed);
}

function sweepParameters() {
  const parameters = {};
  for (const row of $("sweep-parameters").tBodies[0].rows) {
    const [path, values] = [...row.querySelectorAll("input")].map((el) => el.value.trim());
    if (path) parameters[path] = sweepValues(values);
  }
  return parameters;
}

function countVariants() {
  const lists = Object.values(sweepParameters());
  const n = lists.reduce((product, values) => product * values.length, 1);
  $("sweep-count").textContent = lists.length ? `${n} variant${n === 1 ? "" : "s"}, each a job of its own` : "";
}

// A refusal's `parameters['striker.velocity'][1]`, shown under that field's row.
function markSweepRows(problems) {
  const rows = [...$("sweep-parameters").tBodies[0].rows];
  for (const row of rows) {
    row.querySelector(".row-problem").textContent = "";
    row.querySelector(".values").removeAttribute("aria-invalid");
  }
  for (const { field, message } of problems) {
    const match = /^parameters\['([^']+)'\](?:\[(\d+)\])?/.exec(field);
    const row = match && rows.find((r) => r.querySelector(".path").value.trim() === match[1]);
    if (!row) continue;
    const value = match[2] === undefined ? "" : `value ${Number(match[2]) + 1}: `;
    row.querySelector(".row-problem").textContent = `${value}${message}`;
    row.querySelector(".values").setAttribute("aria-invalid", "true");
  }
}

async function submitSweep(event) {
  event.preventDefault();
  const box = $("sweep-errors");
  const edited = editedCase(box);
  if (!edited) return;
  await send("/v1/sweeps", JSON.stringify({ case: edited, parameters: sweepParameters() }), {
    button: $("run-sweep"), box, what: "sweep", open: (sweep) => openSweep(sweep.id), refused: markSweepRows,
  });
}

// ---------------------------------------------------------------------------------------------
// A sweep on view, polled until every variant has finished.

// `view`: {id, sort: {column, descending}, x, y, answer}.
export async function openSweep(id) {
  const signal = showView("sweep-view", `#sweep=${id}`);
  const view = { id, sort: null, x: null, y: "peak_contact_force", answer: null };
  const box = $("sweep-view");
  // Laid out before the first answer, so that nothing moves when it comes.
  box.replaceChildren(
    h("div", { class: "job-head" }, h("h2", { class: "sweep-title" }, `Sweep ${id}`),
      h("span", { class: "badge sweep-status" }, "…"),
      h("button", { type: "button", class: "sweep-cancel", hidden: true, onclick: () => cancelSweep(view) }, "Cancel")),
    h("div", { class: "progress" }, h("div", { class: "sweep-bar progress-bar" })),
    h("p", { class: "muted small sweep-counts" }, ""),
    h("div", { class: "banner error sweep-error", hidden: true }),
    card("Summary quantity against a swept field", chartFigure("sweep", "The variants' results", {
      controls: h("div", { class: "chart-controls sweep-axes" },
        h("label", {}, "Quantity ", h("select", { class: "sweep-y", onchange: (e) => { view.y = e.target.value; drawSweep(view); } })),
        h("label", {}, "against ", h("select", { class: "sweep-x", onchange: (e) => { view.x = e.target.value; drawSweep(view); } }))),
    })),
    card("Variants", h("div", { class: "scroll sweep-table" })));
  const finished = await poll(`/v1/sweeps/${id}`, {
    signal, every: SWEEP_POLL_MS, done: (answer) => answer.finished,
    update: (answer) => { view.answer = answer; renderSweep(view); },
    failed: (error) => sweepError(describe(error)),
  });
  if (finished) refreshJobs();
}

function sweepError(message) {
  const banner = $("sweep-view").querySelector(".sweep-error");
  banner.textContent = message;
  banner.hidden = !message;
}

async function cancelSweep(view) {
  try {
    await api(`/v1/sweeps/${view.id}`, { method: "DELETE" });
  } catch (error) {
    sweepError(`Cancel failed: ${describe(error)}`);
  }
}

function renderSweep(view) {
  const { answer } = view;
  const box = $("sweep-view");
  sweepError("");
  box.querySelector(".sweep-title").replaceChildren(answer.name || "(unnamed)", " sweep",
    h("span", { class: "muted small id" }, answer.id));
  const status = answer.finished ? (answer.counts.succeeded === answer.total ? "succeeded" : "finished") : "running";
  box.querySelector(".sweep-status").textContent = status;
  box.querySelector(".sweep-status").className = `badge sweep-status ${status}`;
  box.querySelector(".sweep-cancel").hidden = answer.finished;
  const percent = Math.round(100 * answer.progress);
  const bar = box.querySelector(".sweep-bar");
  bar.style.width = `${percent}%`;
  bar.textContent = `${percent}%`;
  bar.className = `sweep-bar progress-bar ${status}`;
  box.querySelector(".sweep-counts").textContent = `${answer.total} variants over ${answer.parameters.join(" × ")}: ` +
    Object.entries(answer.counts).map(([s, n]) => `${n} ${s}`).join(", ");
  const shownColumns = Object.keys(SWEEP_COLUMNS).filter((c) => answer.rows.some((r) => r[c] !== null && r[c] !== undefined));
  // The user's choice stays in the view while the columns it needs have not come yet.
  fillSelect(box.querySelector(".sweep-x"), answer.parameters.map((p) => [p, p]), view.x ?? answer.parameters[0]);
  fillSelect(box.querySelector(".sweep-y"), shownColumns.map((c) => [c, SWEEP_COLUMNS[c][0]]), view.y);
  box.querySelector(".sweep-table").replaceChildren(sweepTable(view, shownColumns));
  drawSweep(view);
}

// A select's options, rebuilt only when they change (a redraw must not close an open list).
function fillSelect(select, options, chosen) {
  const key = JSON.stringify(options);
  if (select.dataset.options !== key) {
    select.replaceChildren(...options.map(([value, label]) => h("option", { value }, label)));
    select.dataset.options = key;
  }
  if (options.some(([value]) => value === chosen)) select.value = chosen;
}

// A swept value as the user gave it (4.5, not 4.500).
const valueText = (value) => (typeof value === "number" ? String(+value.toPrecision(6)) : String(value));

const columnText = (column, value) => {
  if (value === null || value === undefined) return "—";
  const inUnit = columnValue(column, value);
  return inUnit === value && Number.isInteger(value) ? String(value) : fmt(inUnit);
};

function sweepRows(view) {
  const rows = view.answer.rows.map((row, i) => ({ ...row, index: i + 1 }));
  if (!view.sort) return rows;
  const { column, descending } = view.sort;
  const key = (row) => (column in SWEEP_COLUMNS ? row[column] : column === "status" ? row.status : row.values[column]);
  const sign = descending ? -1 : 1;
  // Rows without the value (running, failed) last, whichever way.
  return rows.sort((a, b) => {
    const [p, q] = [key(a), key(b)];
    if (p === null || p === undefined) return q === null || q === undefined ? a.index - b.index : 1;
    if (q === null || q === undefined) return -1;
    return (p < q ? -1 : p > q ? 1 : a.index - b.index) * sign;
  });
}

function sweepTable(view, shownColumns) {
  const { answer } = view;
  const sortButton = (column, label) => {
    const sorted = view.sort && view.sort.column === column;
    return h("th", { "aria-sort": sorted ? (view.sort.descending ? "descending" : "ascending") : "none", "data-column": column },
      h("button", { type: "button", class: "sort", onclick: () => {
        view.sort = { column, descending: sorted ? !view.sort.descending : false };
        renderSweep(view);
        $("sweep-view").querySelector(`th[data-column="${CSS.escape(column)}"] button`).focus();
      } }, label, h("span", { class: "arrow", "aria-hidden": "true" }, sorted ? (view.sort.descending ? " ▼" : " ▲") : "")));
  };
  const head = [h("th", {}, "#"), ...answer.parameters.map((p) => sortButton(p, p)), sortButton("status", "status"),
    ...shownColumns.map((c) => sortButton(c, `${SWEEP_COLUMNS[c][0]}${columnUnit(c) ? ` (${columnUnit(c)})` : ""}`))];
  return h("table", { class: "sweep" },
    h("thead", {}, h("tr", {}, head)),
    h("tbody", {}, sweepRows(view).map((row) => h("tr", { "data-job": row.job, class: row.status },
      h("th", {}, h("button", { type: "button", class: "link", title: "open this variant's job",
                                onclick: () => openJob(row.job) }, String(row.index))),
      answer.parameters.map((p) => h("td", { class: "num" }, valueText(row.values[p]))),
      h("td", { title: row.error || "" }, h("span", { class: `badge ${row.status}` }, row.status)),
      shownColumns.map((c) => h("td", { class: "num", "data-column": c }, columnText(c, row[c])))))));
}

// The chosen quantity against the chosen field: a line per combination of the other fields' values.
function sweepTraces({ answer, x, y }) {
  const [label] = SWEEP_COLUMNS[y];
  const unit = columnUnit(y);
  const others = answer.parameters.filter((p) => p !== x);
  const lines = new Map();
  for (const row of answer.rows) {
    if (row[y] === null || row[y] === undefined) continue;
    const name = others.map((p) => `${p} = ${valueText(row.values[p])}`).join(", ") || label;
    if (!lines.has(name)) lines.set(name, []);
    lines.get(name).push([row.values[x], columnValue(y, row[y])]);
  }
  const traces = [...lines].map(([name, points], i) => {
    points.sort((a, b) => a[0] - b[0]);
    return { type: "scatter", mode: "lines+markers", name, x: points.map((q) => q[0]), y: points.map((q) => q[1]),
             line: { color: PALETTE[i % PALETTE.length], width: 1.6 },
             hovertemplate: `%{y:.4g} ${unit} at ${plain(x)} = %{x:.4g}<extra></extra>` };
  });
  return { traces, layout: { showlegend: traces.length > 1, xaxis: { title: { text: plain(x) } },
                             yaxis: { title: { text: axisTitle(label, unit) } } } };
}

// The table as CSV, every value in SI.
function sweepCsv({ answer }) {
  const columns = Object.keys(SWEEP_COLUMNS);
  const text = csvText(["job", ...answer.parameters, "status", ...columns],
    answer.rows.map((row) => [row.job, ...answer.parameters.map((p) => row.values[p]), row.status, ...columns.map((c) => row[c])]));
  return { blob: new Blob([text], { type: "text/csv" }), name: `sweep-${answer.id}.csv` };
}

function drawSweep(view) {
  const box = $("sweep-view");
  const [x, y] = [box.querySelector(".sweep-x").value, box.querySelector(".sweep-y").value];
  if (!x || !y) return null; // no variant has finished yet
  return drawChart(box.querySelector('[data-chart="sweep"]'), {
    data: { answer: view.answer, x, y }, build: sweepTraces, file: `sweep-${view.answer.id}-${y}`,
    csv: async () => sweepCsv(view) });
}

export function startSweeps() {
  SWEEP_START.forEach(addSweepRow);
  $("add-sweep-field").addEventListener("click", () => addSweepRow().querySelector("input").focus());
  $("sweep-form").addEventListener("submit", submitSweep);
}
