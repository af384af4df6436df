// Signal matching on the page: its form (a pile's head record chosen on disk, matched over the pile
// in the editor) and a finished match in the job view (a match is a job: the job view polls it):
// the capacity and how the shaft and the toe share it, the fit, and four charts: the force at the
// gauges, the waves down and up, the resistance along the pile, and the static load test.
import { describe, getJSON } from "./api.js";
import { axisTitle, chartFigure, csvText, displayUnit, drawChart, PALETTE, scaled } from "./charts.js";
import { $, card, fmt, h, showProblems, table, typed } from "./dom.js";
import { editedCase, send } from "./editor.js";
import { showJobError } from "./job.js";
import { chooseRecordFile } from "./records.js";
import { fitCards, rows } from "./studies.js";
import { shownUnit } from "./units.js";

export const SIGNAL_MATCHES = "/v1/signal-matches";
// What the record takes the place of: the hammer above the gauges. A pile case from the editor (the
// pile preset, say) is sent without them, as the form says.
const DRIVEN_BY_THE_RECORD = ["striker", "contact", "anvil", "struck_end", "blows", "cycles", "drive"];

let chosen = null; // the record file's input (records.js): its record read, or null

// A pile's head record as the API's JSON. Only its shape is read here (a header
// `time,force@X,velocity@X`, comment lines `# …`): the service checks the samples and names any bad
// one, which `lines` maps back to its line in the file.
function parsePileRecord(text) {
  const found = [];
  text.split(/\r?\n/).forEach((line, i) => {
    if (line.trim() && !line.trim().startsWith("#")) found.push([i + 1, line.split(",").map((cell) => cell.trim())]);
  });
  if (!found.length) throw [{ field: "record", message: "the file is empty" }];
  const [[headerLine, header], ...samples] = found;
  const columns = header.slice(1).map((cell) => /^(force|velocity)@(.+)$/.exec(cell));
  const stations = new Set(columns.map((m) => m && m[2]));
  if (header[0] !== "time" || columns.length !== 2 || columns.some((m) => !m) || columns[0][1] === columns[1][1]
      || stations.size !== 1) {
    throw [{ field: `line ${headerLine}`, message: `must be the header time,force@X,velocity@X (X the gauges' station, m); found ${header.join(",")}` }];
  }
  const odd = samples.find(([, cells]) => cells.length !== 3);
  if (odd) throw [{ field: `line ${odd[0]}`, message: `has ${odd[1].length} columns: give time,force,velocity` }];
  const column = (k) => samples.map(([, cells]) => typed(cells[k]));
  const record = { x: typed(columns[0][2]), time: column(0), [columns[0][1]]: column(1), [columns[1][1]]: column(2) };
  return { record, lines: samples.map(([line]) => line) };
}

function describeRecord(record) {
  const span = record.time.at(-1) - record.time[0];
  const unit = displayUnit({ unit: "s" }, span);
  return `${record.time.length} samples of force and velocity at x = ${fmt(record.x)} m over `
    + `${fmt(scaled([span], unit)[0])} ${unit}`;
}

async function submitMatch(event) {
  event.preventDefault();
  const box = $("match-errors");
  const edited = editedCase(box);
  if (!edited) return;
  if (!chosen.measured) {
    showProblems(box, "Choose the pile's head record (CSV) first.");
    return;
  }
  const pile = Object.fromEntries(Object.entries(edited).filter(([name]) => !DRIVEN_BY_THE_RECORD.includes(name)));
  const parameters = rows("match-parameters");
  const body = { case: pile, record: chosen.measured.record, ...(Object.keys(parameters).length ? { parameters } : {}) };
  await send(SIGNAL_MATCHES, JSON.stringify(body),
             { button: $("run-match"), box, what: "signal match", where: chosen.line });
}

// ---------------------------------------------------------------------------------------------
// A finished match in the job view.

export async function showSignalMatch(view) {
  let study;
  try {
    study = await getJSON(`${SIGNAL_MATCHES}/${view.id}`);
  } catch (error) {
    if (!view.signal.aborted) showJobError(`The signal match could not be loaded: ${describe(error)}`);
    return;
  }
  if (view.signal.aborted) return;
  const { match } = study;
  const charts = CHARTS.map(([name, title, build, csv]) => [chartFigure(name, title), build, csv]);
  $("study").replaceChildren(capacityCard(match), ...fitCards(match),
    card("Match", h("div", { class: "chart-grid" }, charts.map(([figure]) => figure))));
  await Promise.all(charts.map(([figure, build, csv]) => drawChart(figure, {
    data: match, build, file: `${figure.dataset.chart}-${study.id}`,
    csv: async () => ({ blob: new Blob([csv(match)], { type: "text/csv" }), name: `${figure.dataset.chart}-${study.id}.csv` }),
  })));
}

// The capacity and how the shaft and the toe share it, each with its standard error.
function capacityCard(match) {
  const kn = (v) => (typeof v === "number" ? fmt(v / 1e3) : "not determined");
  const num = (text, className) => h("td", { class: className }, text);
  const row = (label, value, error) => h("tr", {}, h("th", {}, label), num(kn(value), "num value"), num(kn(error), "num"));
  const quality = match.match_quality;
  return card("Capacity",
    table("capacity", ["", "kN", "standard error (kN)"], [
      row("Total (static)", match.capacity.value, match.capacity.standard_error),
      ...match.resistance_distribution.map((part) => row(part.part, part.resistance, part.standard_error)),
    ]),
    h("p", { class: "muted small match-quality", title: match.match_quality_definition },
      `Match quality ${fmt(quality.value, 3)}: ${fmt(quality.window, 3)} over the 2L/c window, `
      + `${quality.after === null ? "—" : fmt(quality.after, 3)} after it (0 is a perfect match). `
      + `Case method RMX ${match.case_method.map((r) => `${r.damping_factor}: ${kn(r.capacity)}`).join(", ")} kN.`));
}

const kN = () => shownUnit("force");
const timeAxis = (match) => displayUnit({ unit: "s" }, match.series.time.at(-1));
const timed = (match, values, name, i, dots) => ({
  type: "scatter", mode: dots ? "markers" : "lines", name, x: scaled(match.series.time, timeAxis(match)),
  y: scaled(values, kN()), ...(dots ? { marker: { color: PALETTE[i], size: 3, opacity: 0.6 } }
    : { line: { color: PALETTE[i], width: 1.5 } }),
  hovertemplate: `%{y:.4g} ${kN()} at %{x:.4g} ${timeAxis(match)}<extra>${name}</extra>`,
});
const timeLayout = (match, label) => ({
  showlegend: true, xaxis: { title: { text: axisTitle("Time", timeAxis(match)) } },
  yaxis: { title: { text: axisTitle(label, kN()) } },
});

// The force at the gauges, measured and computed; the 2L/c window where the soil first answers shaded.
function forceChart(match) {
  const [start, end] = scaled(match.match_quality.window_time, timeAxis(match));
  const layout = timeLayout(match, "Force at the gauges");
  layout.shapes = [{ type: "rect", xref: "x", yref: "paper", x0: start, x1: end, y0: 0, y1: 1, layer: "below",
                     fillcolor: "#000", opacity: 0.07, line: { width: 0 } }];
  return { traces: [timed(match, match.series.record, "measured", 7, true), timed(match, match.series.model, "computed", 0)],
           layout };
}

// The waves going down and coming up, (F ± Z·v)/2, measured (dots) and computed (lines).
function wavesChart(match) {
  const { measured: m, computed: c } = match.waves;
  return {
    traces: [timed(match, m.down, "down, measured", 1, true), timed(match, c.down, "down, computed", 1),
             timed(match, m.up, "up, measured", 2, true), timed(match, c.up, "up, computed", 2)],
    layout: timeLayout(match, "(F ± Z·v)/2"),
  };
}

// Each part's fitted resistance as a bar over its span below the gauges (the toe's just below the
// end), with 3 standard errors.
function resistanceChart(match) {
  const rows = match.resistance_distribution;
  const length = rows.at(-1).to;
  const span = (row) => (row.part === "toe" ? [length, length / 30] : [row.from, row.to - row.from]);
  const bar = {
    type: "bar", orientation: "h", name: "resistance", y: rows.map((r) => span(r)[0] + span(r)[1] / 2),
    width: rows.map((r) => span(r)[1]), x: scaled(rows.map((r) => r.resistance), kN()), text: rows.map((r) => r.part),
    marker: { color: rows.map((r) => (r.part === "toe" ? PALETTE[1] : PALETTE[0])) },
    error_x: { type: "data", array: scaled(rows.map((r) => 3 * (r.standard_error ?? 0)), kN()), visible: true },
    hovertemplate: `%{text}: %{x:.4g} ${kN()}<extra></extra>`,
  };
  return { traces: [bar], layout: { showlegend: false,
    xaxis: { title: { text: axisTitle("Fitted resistance, ± 3 standard errors", kN()) }, rangemode: "tozero" },
    yaxis: { title: { text: axisTitle("Below the gauges", "m") }, range: [1.05 * length, 0] } } };
}

// The static load test of the fitted soil: the settlement downward under the load.
function loadTestChart(match) {
  const { load, settlement } = match.static_load_test;
  const mm = shownUnit("length");
  return { traces: [{ type: "scatter", mode: "lines+markers", name: "load test", x: scaled(load, kN()),
                      y: scaled(settlement, mm), line: { color: "#222", width: 1.5 }, marker: { size: 4 },
                      hovertemplate: `%{y:.4g} ${mm} under %{x:.4g} ${kN()}<extra></extra>` }],
           layout: { showlegend: false, xaxis: { title: { text: axisTitle("Load at the head", kN()) }, rangemode: "tozero" },
                     yaxis: { title: { text: axisTitle("Settlement", mm) }, autorange: "reversed" } } };
}

// Each chart: its name, title, build, and its data as CSV (SI).
const CHARTS = [
  ["match-force", "Force at the gauges, measured and computed", forceChart,
    (m) => csvText(["time_s", "measured_force_N", "computed_force_N"],
      m.series.time.map((t, k) => [t, m.series.record[k], m.series.model[k]]))],
  ["match-waves", "Waves down and up, (F ± Z·v)/2", wavesChart,
    (m) => csvText(["time_s", "down_measured_N", "down_computed_N", "up_measured_N", "up_computed_N"],
      m.waves.time.map((t, k) => [t, m.waves.measured.down[k], m.waves.computed.down[k], m.waves.measured.up[k],
        m.waves.computed.up[k]]))],
  ["match-resistance", "Fitted resistance along the pile", resistanceChart,
    (m) => csvText(["part", "from_m", "to_m", "resistance_N", "standard_error_N"],
      m.resistance_distribution.map((r) => [r.part, r.from, r.to, r.resistance, r.standard_error]))],
  ["match-load-test", "Static load test of the fitted soil", loadTestChart,
    (m) => csvText(["load_N", "settlement_m"], m.static_load_test.load.map((l, k) => [l, m.static_load_test.settlement[k]]))],
];

export function startMatching() {
  chosen = chooseRecordFile({ input: "match-record-file", info: "match-record-info", box: "match-errors",
    parse: parsePileRecord, described: describeRecord,
    unreadable: (name) => `${name} is not a pile's head record, so it cannot be matched.` });
  $("match-form").addEventListener("submit", submitMatch);
}
