// Calibrations and optimisations on the page: their forms (over the case in the editor) and a
// finished study's answer in the job view (a study is a job: the job view polls it); a fit's cards
// also serve the signal match's view (matching.js).
import { describe, getJSON } from "./api.js";
import { $, card, fmt, h, save, showProblems, table, typed } from "./dom.js";
import { editedCase, loadCase, send } from "./editor.js";
import { showImage, showJobError } from "./job.js";
import { chooseRecordFile } from "./records.js";
import { pulseCard, warningsBanner } from "./summary.js";
import { shown, shownUnit } from "./units.js";

// The rows each form starts with: [field, low, high]; a limit's is [quantity, "max" or "min", value].
const STARTING_ROWS = {
  "fit-parameters": [["contact.stiffness", "1e9", "1e15"], ["medium.stiffness", "1e7", "1e11"]],
  variables: [["striker.length", "0.1", "0.6"]],
  limits: [],
};

let chosen = null; // the record file's input (records.js): its record read, or null

export function addRow(tableId, [path, second, third] = ["", "", ""]) {
  const limit = tableId === "limits";
  const input = (value, label, className, list) =>
    h("input", { value, class: className, list, spellcheck: "false", "aria-label": label });
  const row = h("tr", {},
    h("td", {}, input(path, limit ? "quantity" : "field", "path", limit ? "quantities" : "fields")),
    h("td", {}, limit
      ? h("select", { "aria-label": "side" }, h("option", { value: "max", selected: second !== "min" }, "≤"),
          h("option", { value: "min", selected: second === "min" }, "≥"))
      : input(second, "low", "number")),
    h("td", {}, input(third, limit ? "limit" : "high", "number")),
    h("td", {}, h("button", { type: "button", class: "link remove", "aria-label": "remove this row",
                              title: "remove this row", onclick: () => row.remove() }, "✕")));
  $(tableId).tBodies[0].append(row);
  return row;
}

// A form's table as {path: [low, high]}, or for limits {quantity: {max or min: value}}.
export function rows(tableId) {
  const out = {};
  for (const row of $(tableId).tBodies[0].rows) {
    const [path, second, third] = [...row.querySelectorAll("input, select")].map((el) => el.value.trim());
    if (!path) continue;
    if (tableId === "limits") out[path] = { ...out[path], [second]: typed(third) };
    else out[path] = [typed(second), typed(third)];
  }
  return out;
}

// A CSV record as the API's JSON. Only its shape is read here (a header `time,<quantity>` and two
// columns, or `<quantity>` and one column, with comment lines `# sample_rate = …`, `# time_start =
// …`, `# time_offset = …` before the header): the service checks the samples and names any bad
// one, which `lines` maps back to its line in the file.
const CLOCK_FIELDS = ["time_start", "sample_rate", "time_offset"];

function parseRecord(text) {
  const found = [];
  const clock = {};
  text.split(/\r?\n/).forEach((line, i) => {
    if (!line.trim()) return;
    if (line.trim().startsWith("#")) {
      const [name, ...value] = line.trim().slice(1).split("=");
      if (!found.length && value.length && CLOCK_FIELDS.includes(name.trim())) clock[name.trim()] = typed(value.join("=").trim());
      return;
    }
    found.push([i + 1, line.split(",").map((cell) => cell.trim())]);
  });
  if (!found.length) throw [{ field: "record", message: "the file is empty" }];
  const [[headerLine, header], ...samples] = found;
  const timed = header.length === 2 && header[0] === "time";
  const known = /^(contact_force|medium_force|struck_end_velocity|working_end_velocity|stress@.*)$/;
  if (!timed && (header.length !== 1 || !known.test(header[0]))) {
    throw [{ field: `line ${headerLine}`, message: `must be the header time,<quantity> (or <quantity> alone, with # sample_rate = … above it); found ${header.join(",")}` }];
  }
  const odd = samples.find(([, cells]) => cells.length !== header.length);
  if (odd) throw [{ field: `line ${odd[0]}`, message: `has ${odd[1].length} columns: give ${timed ? "time,value" : "one value"}` }];
  const label = header.at(-1);
  const stress = label.startsWith("stress@");
  const record = {
    quantity: stress ? "stress" : label,
    ...(stress ? { x: typed(label.slice("stress@".length)) } : {}),
    ...clock,
    ...(timed ? { time: samples.map(([, cells]) => typed(cells[0])) } : {}),
    values: samples.map(([, cells]) => typed(cells.at(-1))),
  };
  return { record, lines: samples.map(([line]) => line) };
}

// What a record read says: its samples, quantity, rate and span.
function describeRecord(record) {
  const count = record.values.length;
  const [first, last] = record.time ? [record.time[0], record.time.at(-1)]
    : [record.time_start || 0, (record.time_start || 0) + (count - 1) / record.sample_rate];
  const span = Number.isFinite(first) && Number.isFinite(last)
    ? ` over ${fmt(shown(first, "time"))}–${fmt(shown(last, "time"))} ${shownUnit("time")}` : "";
  const rate = record.sample_rate
    ? ` at ${fmt(shown(record.sample_rate, "frequency"))} ${shownUnit("frequency")}` : "";
  const where = record.quantity === "stress" ? ` at x = ${fmt(record.x)} m` : "";
  return `${count} samples of ${record.quantity}${where}${rate}${span}`;
}

async function submitCalibration(event) {
  event.preventDefault();
  const box = $("calibration-errors");
  const edited = editedCase(box);
  if (!edited) return;
  if (!chosen.measured) {
    showProblems(box, "Choose the record's CSV file first.");
    return;
  }
  const body = JSON.stringify({ case: edited, record: chosen.measured.record, parameters: rows("fit-parameters") });
  await send("/v1/calibrations", body, { button: $("fit"), box, what: "calibration", where: chosen.line });
}

async function submitOptimization(event) {
  event.preventDefault();
  const box = $("optimization-errors");
  const edited = editedCase(box);
  if (!edited) return;
  const body = JSON.stringify({
    case: edited, variables: rows("variables"), limits: rows("limits"),
    objective: { [$("goal").value]: $("objective").value.trim() },
    max_evaluations: typed($("evaluations").value.trim()),
  });
  await send("/v1/optimizations", body, { button: $("optimize"), box, what: "optimisation" });
}

// ---------------------------------------------------------------------------------------------
// A finished study in the job view.

const num = (text, className = "num") => h("td", { class: className }, text);

// Each study kind the job view shows: its route, its answer's name, its cards and its plot's title.
const STUDY_VIEWS = {
  calibration: { route: "calibrations", answer: "fit", cards: (fit) => fitCards(fit),
                 title: "The record against the fitted model" },
  optimization: { route: "optimizations", answer: "optimum", cards: (optimum) => optimumCards(optimum),
                  title: "Every run of the objective" },
};

export async function showStudy(view, kind) {
  const spec = STUDY_VIEWS[kind];
  let study;
  try {
    study = await getJSON(`/v1/${spec.route}/${view.id}`);
  } catch (error) {
    if (!view.signal.aborted) showJobError(`The ${kind.replace("_", " ")} could not be loaded: ${describe(error)}`);
    return;
  }
  if (view.signal.aborted) return;
  const { title } = spec;
  const plot = { name: kind, title, links: { png: study.links.plot_png, svg: study.links.plot_svg } };
  const frame = h("div", { class: "frame loading" });
  const figure = card("Plot", h("figure", { class: "plot wide", "data-plot": kind }, frame, h("figcaption", {}, title)));
  $("study").replaceChildren(...spec.cards(study[spec.answer]), figure);
  await showImage(frame, plot, view);
}

// A fit's cards: its warnings, its parameters with their uncertainty and correlation, and its actions.
export function fitCards(fit) {
  const names = Object.keys(fit.parameters);
  const parameters = names.map((name) => {
    const p = fit.parameters[name];
    const known = typeof p.standard_error === "number";
    return h("tr", { "data-parameter": name }, h("th", {}, name), num(fmt(p.value), "num value"),
      num(known ? fmt(p.standard_error) : "not determined"),
      num(known && p.value ? fmt((100 * p.standard_error) / Math.abs(p.value), 2) : "—"),
      num(fmt(p.low)), num(fmt(p.high)));
  });
  const correlation = names.length > 1 && h("details", { open: true, class: "correlation" },
    h("summary", {}, "Correlation of the parameters"),
    table("correlation", ["", ...names], names.map((name, i) => h("tr", {}, h("th", {}, name),
      fit.correlation[i].map((r, j) => num(fmt(r, 3), i !== j && Math.abs(r) >= 0.95 ? "num strong" : "num"))))));
  const file = `${(fit.case && fit.case.name) || "case"}-fit.json`;
  return [
    warningsBanner(fit.warnings),
    card("Fit",
      table("fit", ["parameter", "value", "standard error", "± %", "95% low", "95% high"], parameters),
      h("p", { class: "muted small fit-figures" },
        `Misfit (normalised RMS) ${fmt(fit.nrmse, 3)}, the record's own noise ${fmt(fit.noise, 3)} · `,
        `${fit.evaluations} model runs in ${fmt(fit.seconds, 3)} s · ${fit.grid.cells} cells`),
      correlation,
      h("div", { class: "actions" },
        h("button", { type: "button", onclick: () => loadCase(fit.case) }, "Load the fitted case"),
        h("button", { type: "button", onclick: () => save(new Blob([JSON.stringify(fit, null, 2)],
          { type: "application/json" }), file) }, "Download the fit (JSON)"))),
  ];
}

function optimumCards(optimum) {
  const paths = Object.keys(optimum.variables);
  const goal = Object.keys(optimum.objective)[0];
  const objective = optimum.objective[goal];
  const limitText = (name) => Object.entries(optimum.limits[name] || {})
    .map(([side, value]) => `${side === "max" ? "≤" : "≥"} ${fmt(value)}`).join(", ");
  const quantities = [objective, ...Object.keys(optimum.limits)];
  const found = optimum.values !== null;
  const best = found && card("Best design",
    table("optimum", ["", "value", "bounds"], [
      paths.map((path) => h("tr", { "data-variable": path }, h("th", {}, path), num(fmt(optimum.values[path]), "num value"),
        num(`${fmt(optimum.variables[path][0])} – ${fmt(optimum.variables[path][1])}`))),
      quantities.map((name) => h("tr", { "data-quantity": name, class: name === objective ? "highlight" : null },
        h("th", {}, name === objective ? `${name} (${goal === "maximize" ? "maximised" : "minimised"})` : name),
        num(fmt(optimum.quantities[name]), "num value"), num(name === objective ? "" : limitText(name)))),
    ]),
    h("p", { class: "muted small" }, "Solved again under the tolerance; its pulse summary is below."),
    h("div", { class: "actions" },
      h("button", { type: "button", onclick: () => loadCase(optimum.case) }, "Load the best case")));
  const columns = [...paths, ...quantities];
  const history = h("details", { class: "history" },
    h("summary", {}, `All ${optimum.history.length} runs`),
    h("div", { class: "scroll" }, table("history", ["#", ...columns, "within limits"],
      optimum.history.map((run, i) => h("tr", { class: run.feasible ? null : "infeasible" },
        num(String(i + 1)), paths.map((p) => num(fmt(run.values[p]))),
        quantities.map((q) => num(fmt(run.quantities[q]))), num(run.feasible ? "yes" : "no"))))),
    h("button", { type: "button", onclick: () => save(new Blob([historyCsv(optimum.history, paths, quantities)],
      { type: "text/csv" }), "runs.csv") }, "Download the runs (CSV)"));
  return [
    warningsBanner(optimum.warnings),
    best,
    card("Search",
      h("p", { class: "stopped" }, h("strong", {}, "Stopped: "), optimum.stopped),
      h("p", { class: "muted small" }, `${optimum.evaluations} model runs in ${fmt(optimum.seconds, 3)} s on `,
        `${optimum.grid.cells} cells`, optimum.runs_spread
          ? ` · runs here ${optimum.runs_spread.here}, on other workers ${optimum.runs_spread.other_workers}` : ""),
      history),
    found && pulseCard(optimum.summary),
  ].filter(Boolean);
}

function historyCsv(history, paths, quantities) {
  const lines = [["run", ...paths, ...quantities, "feasible"].join(",")];
  history.forEach((run, i) => lines.push([i + 1, ...paths.map((p) => run.values[p]),
    ...quantities.map((q) => run.quantities[q] ?? ""), run.feasible].join(",")));
  return `${lines.join("\n")}\n`;
}

export function startStudies() {
  for (const [tableId, starting] of Object.entries(STARTING_ROWS)) starting.forEach((row) => addRow(tableId, row));
  document.querySelectorAll("[data-add]").forEach((button) =>
    button.addEventListener("click", () => addRow(button.dataset.add).querySelector("input").focus()));
  chosen = chooseRecordFile({ input: "record-file", info: "record-info", box: "calibration-errors",
    parse: parseRecord, described: describeRecord, unreadable: (name) => `${name} is not a record, so it cannot be fitted.` });
  $("calibration-form").addEventListener("submit", submitCalibration);
  $("optimization-form").addEventListener("submit", submitOptimization);
}
