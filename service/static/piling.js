// The pile studies on the page: the bearing graph (or the inspector's chart) and the drivability,
// their forms over the case in the editor, and a finished one in the job view (a study is a job: the
// job view polls it): a chart of the blow count with the stresses on a second axis, and a table of
// its rows, each a variant driven until its set settled.
import { describe, getJSON } from "./api.js";
import { axisTitle, chartFigure, csvText, drawChart, PALETTE } from "./charts.js";
import { $, card, fmt, h, showProblems, typed } from "./dom.js";
import { editedCase, send } from "./editor.js";
import { showJobError } from "./job.js";
import { warningsBanner } from "./summary.js";
import { sweepValues } from "./sweep.js";
import { shown, shownUnit } from "./units.js";

// Each pile study's kind and its route.
export const PILE_STUDIES = { bearing_graph: "/v1/bearing-graphs", drivability: "/v1/drivability" };

// The soil the drivability form starts with: sand over dense sand (Smith's quakes and damping factors).
const STARTING_SOIL = {
  layers: [
    { from: 0, to: 6, shaft_resistance: 2e4, toe_resistance: 4e5, shaft_quake: 0.00254, toe_quake: 0.00254,
      shaft_damping_factor: 0.16, toe_damping_factor: 0.49 },
    { from: 6, to: 20, shaft_resistance: 5e4, toe_resistance: 1.2e6, shaft_quake: 0.00254, toe_quake: 0.00254,
      shaft_damping_factor: 0.16, toe_damping_factor: 0.49, setup_factor: 1.3 },
  ],
  depths: [2, 4, 6, 8, 10, 12, 14],
  blow_rate: 0.8,
  refusal: 250,
};

// A row's columns (the API's names) as [label, quantity]; a count has none.
const COLUMNS = {
  ultimate_resistance: ["Capacity Rᵤ", "force"],
  stroke: ["Stroke", "depth"],
  depth: ["Depth", "depth"],
  blow_count: ["Blow count", "blow_count"],
  set: ["Set", "length"],
  max_compressive_stress: ["Largest compressive stress", "stress"],
  max_tensile_stress: ["Largest tensile stress", "stress"],
  transferred_energy: ["Transferred energy (EMX)", "energy"],
  error_estimate: ["Estimated error", "ratio"],
  blows: ["Blows", null],
};
const RESULTS = ["blow_count", "set", "max_compressive_stress", "max_tensile_stress", "transferred_energy",
  "error_estimate", "blows"];
const unitOf = (column) => (COLUMNS[column][1] ? shownUnit(COLUMNS[column][1]) : "");
const inUnitOf = (column, value) => (value === null || value === undefined ? null
  : COLUMNS[column][1] ? shown(value, COLUMNS[column][1]) : value);
const heading = (column) => `${COLUMNS[column][0]}${unitOf(column) ? ` (${unitOf(column)})` : ""}`;

// ---------------------------------------------------------------------------------------------
// The forms.

async function submitBearingGraph(event) {
  event.preventDefault();
  const box = $("bearing-errors");
  const edited = editedCase(box);
  if (!edited) return;
  const share = $("toe-share").value.trim();
  const body = { case: edited, [$("bearing-variable").value]: sweepValues($("bearing-values").value),
                 ...(share ? { toe_share: typed(share) } : {}) };
  await send(PILE_STUDIES.bearing_graph, JSON.stringify(body), { button: $("run-bearing"), box, what: "bearing graph" });
}

async function submitDrivability(event) {
  event.preventDefault();
  const box = $("drivability-errors");
  const edited = editedCase(box);
  if (!edited) return;
  let soil;
  try {
    soil = JSON.parse($("soil-json").value);
  } catch (error) {
    showProblems(box, "The soil is not valid JSON, so it was not sent.", [{ field: "soil", message: error.message }]);
    return;
  }
  await send(PILE_STUDIES.drivability, JSON.stringify({ case: edited, soil }),
             { button: $("run-drivability"), box, what: "drivability" });
}

async function readSoilFile() {
  const file = $("soil-file").files[0];
  if (file) $("soil-json").value = await file.text();
}

// ---------------------------------------------------------------------------------------------
// A finished pile study in the job view.

export async function showPileStudy(view, kind) {
  let study;
  try {
    study = await getJSON(`${PILE_STUDIES[kind]}/${view.id}`);
  } catch (error) {
    if (!view.signal.aborted) showJobError(`The ${kind.replace("_", " ")} could not be loaded: ${describe(error)}`);
    return;
  }
  if (view.signal.aborted) return;
  const along = kind === "drivability" ? "depth" : study.variable;
  const title = kind === "drivability" ? "Blow count and largest stresses against the depth"
    : `Blow count and largest stresses against the ${along === "stroke" ? "ram's stroke" : "capacity"}`;
  const figure = chartFigure("pile", title, { wide: true });
  const warnings = [...study.warnings, ...study.rows.flatMap((row) =>
    (row.warnings || []).map((w) => `${COLUMNS[along][0]} ${fmt(inUnitOf(along, row[along]))} ${unitOf(along)}: ${w}`))];
  $("study").replaceChildren(warningsBanner(warnings), kind === "drivability" ? totalsCard(study) : null,
    card(kind === "drivability" ? "Drivability" : along === "stroke" ? "Inspector's chart" : "Bearing graph", figure),
    card("Rows", h("div", { class: "scroll pile-table" }, rowsTable(study, along))));
  await drawChart(figure, { data: { study, along }, build: kind === "drivability" ? drivabilityChart : bearingChart,
                            file: `${kind}-${study.id}`, csv: async () => rowsCsv(study, along) });
}

function totalsCard(study) {
  const minutes = (s) => (s === null ? "—" : `${fmt(s / 60, 3)} min`);
  const depth = (d) => (d === null ? "none" : `${fmt(d, 3)} m`);
  return card("Driving", h("p", { class: "pile-totals" },
    h("strong", {}, "Total blows "), study.total_blows === null ? "—" : fmt(study.total_blows, 4),
    study.driven_to === null ? "" : ` to ${fmt(study.driven_to, 3)} m`,
    " · ", h("strong", {}, "driving time "), minutes(study.driving_time), ` at ${fmt(study.blow_rate, 3)} blows/s`,
    " · ", h("strong", {}, "refusal "), depth(study.refusal_depth), ` (over ${fmt(study.refusal, 4)} blows/m)`,
    study.rows.some((row) => row.restrike) ? [" · ", h("strong", {}, "restrike refusal "), depth(study.restrike_refusal_depth)] : ""));
}

function rowsTable(study, along) {
  const restrike = study.rows.some((row) => row.restrike);
  const cell = (column, value) => h("td", { class: "num", "data-column": column },
    value === null || value === undefined ? "—" : COLUMNS[column][1] ? fmt(inUnitOf(column, value)) : String(value));
  return h("table", { class: "pile" },
    h("thead", {}, h("tr", {}, [along, ...RESULTS].map((c) => h("th", {}, heading(c))),
      restrike ? h("th", {}, `Restrike ${heading("blow_count").toLowerCase()}`) : null)),
    h("tbody", {}, study.rows.map((row) => h("tr", { class: row.error ? "failed" : null, title: row.error || null },
      h("th", { class: "num" }, fmt(inUnitOf(along, row[along]))),
      RESULTS.map((c) => cell(c, row[c])),
      restrike ? cell("blow_count", row.restrike && row.restrike.blow_count) : null))));
}

// The rows as CSV, every value in SI.
function rowsCsv(study, along) {
  const restrike = study.rows.some((row) => row.restrike);
  const text = csvText([along, ...RESULTS, ...(restrike ? ["restrike_blow_count"] : []), "warnings"],
    study.rows.map((row) => [row[along], ...RESULTS.map((c) => row[c]),
      ...(restrike ? [row.restrike && row.restrike.blow_count] : []), (row.warnings || []).length]));
  return { blob: new Blob([text], { type: "text/csv" }), name: `${study.kind}-${study.id}.csv` };
}

const STRESSES = [["max_compressive_stress", "compressive", "dash"], ["max_tensile_stress", "tensile", "dot"]];

// The blow count against the capacity or the stroke, the stresses on the right-hand axis.
function bearingChart({ study, along }) {
  const x = study.rows.map((row) => inUnitOf(along, row[along]));
  const xText = axisTitle(COLUMNS[along][0], unitOf(along));
  const line = (column, name, i, more) => ({
    type: "scatter", mode: "lines+markers", name, x, y: study.rows.map((row) => inUnitOf(column, row[column])),
    line: { color: PALETTE[i], width: 1.6, ...more.line }, yaxis: more.yaxis,
    hovertemplate: `%{y:.4g} ${unitOf(column)} at %{x:.4g} ${unitOf(along)}<extra>${name}</extra>`,
  });
  const traces = [line("blow_count", "blow count", 0, {}),
    ...STRESSES.map(([column, name, dash], i) => line(column, `${name} stress`, i + 1, { line: { dash }, yaxis: "y2" }))];
  return { traces, layout: { showlegend: true, xaxis: { title: { text: xText } },
    yaxis: { title: { text: axisTitle("Blow count", unitOf("blow_count")) }, rangemode: "tozero" },
    yaxis2: { title: { text: axisTitle("Largest stress", unitOf("max_compressive_stress")) }, overlaying: "y",
              side: "right", showgrid: false, rangemode: "tozero" } } };
}

// The blow count (and the restrike's) against the depth, downward; the stresses on the top axis.
function drivabilityChart({ study }) {
  const depth = study.rows.map((row) => row.depth);
  const line = (values, name, i, unit, more = {}) => ({
    type: "scatter", mode: "lines+markers", name, x: values, y: depth, line: { color: PALETTE[i], width: 1.6, ...more.line },
    xaxis: more.xaxis, hovertemplate: `%{x:.4g} ${unit} at %{y:.4g} m<extra>${name}</extra>`,
  });
  const counts = (rows) => rows.map((row) => (row ? row.blow_count : null));
  const traces = [line(counts(study.rows), "blow count", 0, unitOf("blow_count"))];
  if (study.rows.some((row) => row.restrike)) {
    traces.push(line(counts(study.rows.map((row) => row.restrike)), "restrike", 4, unitOf("blow_count")));
  }
  traces.push({ type: "scatter", mode: "lines", name: "refusal", x: [study.refusal, study.refusal],
                y: [depth[0], depth.at(-1)], line: { color: "#555", width: 1, dash: "longdash" }, hoverinfo: "skip" });
  STRESSES.forEach(([column, name, dash], i) => traces.push(line(study.rows.map((row) => inUnitOf(column, row[column])),
    `${name} stress`, i + 1, unitOf(column), { line: { dash }, xaxis: "x2" })));
  return { traces, layout: { showlegend: true,
    xaxis: { title: { text: axisTitle("Blow count", unitOf("blow_count")) }, rangemode: "tozero" },
    xaxis2: { title: { text: axisTitle("Largest stress", unitOf("max_compressive_stress")) }, overlaying: "x",
              side: "top", showgrid: false, rangemode: "tozero" },
    yaxis: { title: { text: axisTitle("Depth", unitOf("depth")) }, autorange: "reversed" },
    margin: { l: 56, r: 12, t: 40, b: 40 } } };
}

export function startPiling() {
  $("soil-json").value = JSON.stringify(STARTING_SOIL, null, 2);
  $("soil-file").addEventListener("change", readSoilFile);
  $("bearing-form").addEventListener("submit", submitBearingGraph);
  $("drivability-form").addEventListener("submit", submitDrivability);
}
