// A succeeded job's plots, drawn here with Plotly from the result's series (GET /v1/jobs/{id}/series):
// zoom, pan and hover in the browser, PNG and SVG at full resolution, the CSV from the service.
// The chart frame and its toolbar (chartFigure, drawChart) serve the comparison and the sweep too.
// Plotly is the global of plotly-cartesian.min.js, a classic script loaded before the modules.
import { describe, download, failure, getJSON } from "./api.js";
import { $, card, h, save } from "./dom.js";
import { inUnit, quantityOfSI, shownUnit } from "./units.js";

export const SCREEN_POINTS = 2000; // samples asked of a history for the screen; the service keeps the peaks
const FIELD_TIMES = 300; // frames and stations of the stress fields for the screen
const FIELD_STATIONS = 400;
const EXPORT_SIZE = { width: 1080, height: 600 }; // px of an exported image, the service's plots' own
const CHART_CONFIG = {
  displaylogo: false,
  responsive: true,
  scrollZoom: false, // the wheel scrolls the page; zoom is by a box or the toolbar
  // The toolbar exports at full resolution; the mode bar's camera would save the screen's samples.
  modeBarButtonsToRemove: ["toImage", "select2d", "lasso2d"],
};
// Colour-blind-safe (Okabe–Ito, then Tol's), one a trace or a job; twelve, for the energy terms.
export const PALETTE = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#332288", "#7f7f7f",
                 "#882255", "#44AA99", "#999933", "#AA4499"];
// Stress: compression (< 0) blue, tension red, zero white (ColorBrewer RdBu).
const DIVERGING = [[0, "#053061"], [0.1, "#2166ac"], [0.2, "#4393c3"], [0.3, "#92c5de"], [0.4, "#d1e5f0"],
  [0.5, "#f7f7f7"], [0.6, "#fddbc7"], [0.7, "#f4a582"], [0.8, "#d6604d"], [0.9, "#b2182b"], [1, "#67001f"]];

// ---------------------------------------------------------------------------------------------
// Units: the API's are SI; the screen's are an engineer's (units.js).

// The service's plots' rule (solver/plots.py time_unit): µs below 2 ms, so a scale reads 0 … 2000 at worst.
const timeUnit = (end) => (end < 2e-3 ? "µs" : "ms");

// The unit an axis ({label, unit} in SI) whose largest value is `end` is shown in.
export function displayUnit(axis, end) {
  const quantity = quantityOfSI(axis.unit);
  if (quantity === "time") return timeUnit(end);
  // a place along the tool reads in metres, as the service's plots; a displacement in mm
  if (quantity === "length" && /along/.test(axis.label)) return axis.unit;
  return quantity ? shownUnit(quantity) : axis.unit || "";
}

// Text from the service or the user, for Plotly, which reads a few HTML tags in its labels: as
// text, never as markup.
export const plain = (text) => String(text).replace(/&/g, "&amp;").replace(/</g, "&lt;").replace(/>/g, "&gt;");

export const axisTitle = (label, unit) => plain(unit ? `${label} (${unit})` : label);

// A value to 4 significant digits without trailing zeros or an exponent: "0.6 ms", "3.455 ms".
const brief = (value) => String(+value.toPrecision(4));

// A horizontal axis' title broken at the space nearest its middle when it is wider than a plot
// `width` px wide can show (at about 6.6 px a character).
function fitTitle(text, width) {
  if (!text || text.length * 6.6 < width - 70) return text;
  const middle = text.length / 2;
  const spaces = [...text.matchAll(/ /g)].map((m) => m.index);
  if (!spaces.length) return text;
  const at = spaces.reduce((best, i) => (Math.abs(i - middle) < Math.abs(best - middle) ? i : best));
  return `${text.slice(0, at)}<br>${text.slice(at + 1)}`;
}

// SI values in `unit`.
export const scaled = (values, unit) => values.map((v) => (v === null ? null : inUnit(v, unit)));

export function largest(arrays) {
  let top = -Infinity;
  for (const values of arrays) for (const v of values) if (v !== null && v > top) top = v;
  return top;
}

function largestMagnitude(rows) {
  let top = 0;
  for (const row of rows) for (const v of row) if (v !== null && Math.abs(v) > top) top = Math.abs(v);
  return top;
}

// `<case>-<job>-<name>`, the case's name reduced to characters safe in any file system (as the HDF5's).
function fileStem(caseName, jobId, name) {
  const safe = String(caseName || "case").replace(/[^A-Za-z0-9_.-]+/g, "_").replace(/^[._]+|[._]+$/g, "");
  return `${safe || "case"}-${jobId}-${name}`;
}

const caseName = (data) => (typeof data.case === "string" ? data.case : data.case && data.case.name);

// ---------------------------------------------------------------------------------------------
// One chart: a figure with a toolbar, a plot area of fixed height, and a line for what went wrong.

const plotArea = (figure) => figure.querySelector(".plot-area");

function chartMessage(figure, text) {
  const line = figure.querySelector(".chart-message");
  line.textContent = text || "";
  line.hidden = !text;
}

// The frame of chart `name`, laid out before its data is fetched, its height set by its `size`
// (charts.css: "short", "tall" or the usual), so that nothing moves when the data comes;
// `controls` go under the plot.
export function chartFigure(name, title, { size = null, wide = false, controls = null } = {}) {
  let figure;
  const tool = (action, text, label) => h("button", {
    type: "button", class: "chart-tool", "data-action": action, "aria-label": label, title: label, disabled: true,
    onclick: (event) => chartAction(figure, action, event.currentTarget),
  }, text);
  figure = h("figure", { class: ["chart", size, wide && "wide"].filter(Boolean).join(" "), "data-chart": name },
    h("figcaption", {}, title),
    h("div", { class: "chart-tools", role: "toolbar", "aria-label": `${title}: zoom and export` },
      tool("zoom-in", "+", "zoom in on the horizontal axis"),
      tool("zoom-out", "−", "zoom out on the horizontal axis"),
      tool("pan-left", "←", "move left"),
      tool("pan-right", "→", "move right"),
      tool("reset", "Reset", "back to the whole chart"),
      tool("png", "PNG", "save as PNG, at full resolution"),
      tool("svg", "SVG", "save as SVG, at full resolution"),
      tool("csv", "CSV", "save the data as CSV, every sample")),
    h("div", { class: "plot-area loading" }),
    controls,
    h("p", { class: "chart-message", role: "status", hidden: true }));
  return figure;
}

// The chart's frame says, in words, why it has no chart.
export function chartUnavailable(figure, reason) {
  const area = plotArea(figure);
  area.classList.remove("loading");
  area.classList.add("unavailable");
  area.replaceChildren(h("p", {}, reason));
  // The toolbar and the controls keep their room (charts.css), so the row's charts stay level.
  figure.classList.add("unavailable");
  figure.querySelectorAll(".chart-tools button, .chart-controls input, .chart-controls select")
    .forEach((control) => { control.disabled = true; });
}

// Beside a wide plot; under a narrower one, at the figure's foot (so never over the axis title),
// where it takes height, never the plot's width: two entries a row where they fit whole.
function chartLegend(width) {
  if (width >= 700) return { orientation: "v", x: 1.02, xanchor: "left", y: 1, yanchor: "top", font: { size: 11 } };
  return { orientation: "h", xref: "container", x: 0, xanchor: "left", yref: "container", y: 0, yanchor: "bottom",
           maxheight: 0.6, font: { size: 11 }, ...(width >= 440 ? { entrywidth: 0.5, entrywidthmode: "fraction" } : {}) };
}

// The layout every chart starts from, for a plot `width` px wide; `layout` adds to it, axis by axis.
function chartLayout(layout, width) {
  const axis = { automargin: true, zeroline: false, gridcolor: "#e8ebf0", linecolor: "#98a2b3", ticks: "outside",
                 tickcolor: "#98a2b3", title: { standoff: 6 } };
  const out = {
    margin: { l: 56, r: 12, t: 10, b: 40 },
    font: { family: "system-ui, -apple-system, 'Segoe UI', Roboto, 'DejaVu Sans', sans-serif", size: 12, color: "#1d2430" },
    paper_bgcolor: "#fff",
    plot_bgcolor: "#fff",
    hovermode: "closest",
    dragmode: "zoom",
    legend: chartLegend(width),
    uirevision: "chart", // a redraw (the slider) keeps the user's zoom
    ...layout,
  };
  for (const key of Object.keys(layout).filter(isAxis)) {
    out[key] = { ...axis, ...layout[key], title: { ...axis.title, ...(layout[key].title || {}) } };
    if (key === "xaxis") out[key].title.text = fitTitle(out[key].title.text, width);
  }
  for (const key of ["xaxis", "yaxis"]) if (!out[key]) out[key] = { ...axis };
  return out;
}

const isAxis = (key) => /^[xy]axis\d*$/.test(key);

// Plots drawn, so that those of a view since replaced can be purged: a plot keeps a listener on
// the window (it follows its width) after it leaves the page.
const drawnPlots = new Set();

function purgeDetached() {
  for (const area of drawnPlots) {
    if (area.isConnected) continue;
    Plotly.purge(area);
    drawnPlots.delete(area);
  }
}

// Draws (or redraws) `chart` in `figure`. `chart`: {data, build(data) → {traces, layout},
// load(full) → data at full resolution, for export, file: the exports' name without its extension,
// csv() → {blob, name}}.
export async function drawChart(figure, chart) {
  figure.chart = chart;
  const area = plotArea(figure);
  let traces, layout;
  try {
    ({ traces, layout } = chart.build(chart.data));
  } catch (error) {
    // data not as expected: said in the frame, not thrown into the page
    chartUnavailable(figure, `Not drawn: ${failure(error)}`);
    return;
  }
  if (area.classList.contains("loading")) {
    area.classList.remove("loading");
    area.replaceChildren();
  }
  const full = chartLayout(layout, area.clientWidth);
  // "Reset" goes back to these: a range the chart sets (the slider's fixed stress scale), else auto.
  chart.home = Object.fromEntries(Object.keys(full).filter(isAxis).map((key) => [key, full[key].range || null]));
  purgeDetached();
  drawnPlots.add(area);
  try {
    await Plotly.react(area, traces, full, CHART_CONFIG);
  } catch (error) {
    chartMessage(figure, `The chart could not be drawn: ${failure(error)}`);
    return;
  }
  figure.querySelectorAll(".chart-tools button").forEach((b) => { b.disabled = false; });
}

// The axis ranges now on screen, `{xaxis: [a, b], ...}`.
function currentRanges(area) {
  const ranges = {};
  for (const key of Object.keys(area._fullLayout || {}).filter(isAxis)) {
    const range = area._fullLayout[key].range;
    if (Array.isArray(range)) ranges[key] = range.map(Number);
  }
  return ranges;
}

function zoom(area, factor, shift = 0) {
  const update = {};
  for (const [key, [a, b]] of Object.entries(currentRanges(area))) {
    if (!key.startsWith("x")) continue;
    const half = ((b - a) / 2) * factor;
    const centre = (a + b) / 2 + shift * (b - a);
    update[`${key}.range`] = [centre - half, centre + half];
  }
  return Plotly.relayout(area, update);
}

function resetZoom(figure) {
  const update = {};
  for (const [key, range] of Object.entries(figure.chart.home)) {
    if (range) update[`${key}.range`] = [...range];
    else update[`${key}.autorange`] = true;
  }
  return Plotly.relayout(plotArea(figure), update);
}

const VIEWING = {
  "zoom-in": (figure) => zoom(plotArea(figure), 0.5),
  "zoom-out": (figure) => zoom(plotArea(figure), 2),
  "pan-left": (figure) => zoom(plotArea(figure), 1, -0.25),
  "pan-right": (figure) => zoom(plotArea(figure), 1, 0.25),
  reset: resetZoom,
};

async function chartAction(figure, action, button) {
  chartMessage(figure, null);
  if (VIEWING[action]) {
    try {
      await VIEWING[action](figure);
    } catch (error) {
      chartMessage(figure, `The chart could not be moved: ${failure(error)}`);
    }
    return;
  }
  button.disabled = true;
  const text = button.textContent;
  button.textContent = "…";
  try {
    if (action === "csv") {
      const { blob, name } = await figure.chart.csv();
      save(blob, name);
    } else {
      await exportImage(figure, action);
    }
  } catch (error) {
    chartMessage(figure, `The ${action.toUpperCase()} could not be made: ${failure(error)}`);
  } finally {
    button.disabled = false;
    button.textContent = text;
  }
}

// The chart at full resolution, drawn off screen with the axis ranges on screen, saved as an image.
async function exportImage(figure, format) {
  const chart = figure.chart;
  const area = plotArea(figure);
  const data = chart.load ? await chart.load(true) : chart.data;
  const { traces, layout } = chart.build(data);
  const full = chartLayout(layout, EXPORT_SIZE.width);
  for (const [key, range] of Object.entries(currentRanges(area))) {
    full[key] = { ...full[key], range, autorange: false };
  }
  const copy = h("div", { class: "chart-offscreen", "aria-hidden": "true" });
  document.body.append(copy);
  try {
    await Plotly.newPlot(copy, traces, { ...full, ...EXPORT_SIZE }, { displaylogo: false, staticPlot: true });
    const url = await Plotly.toImage(copy, { format, ...EXPORT_SIZE, scale: format === "png" ? 2 : 1 });
    save(await (await fetch(url)).blob(), `${chart.file}.${format}`);
  } finally {
    Plotly.purge(copy);
    copy.remove();
  }
}

// CSV text of `rows` (arrays) under `header`; a cell with a comma or a quote is quoted.
export function csvText(header, rows) {
  const cell = (v) => (v === null || v === undefined ? "" : /[",\n]/.test(String(v)) ? `"${String(v).replace(/"/g, '""')}"` : String(v));
  return [header, ...rows].map((row) => row.map(cell).join(",")).join("\n") + "\n";
}

// ---------------------------------------------------------------------------------------------
// The charts of one result's series.

// Lines of a series' JSON (x and y in SI) in display units, coloured in order; `options(s, i)`
// adds to each trace.
function lineTraces(data, options = () => ({})) {
  const xUnit = displayUnit(data.x, largest(data.series.map((s) => s.x)));
  const yUnit = displayUnit(data.y, 0);
  const traces = data.series.map((s, i) => ({
    type: "scatter", mode: "lines", name: plain(s.label), x: scaled(s.x, xUnit), y: scaled(s.y, yUnit),
    line: { color: PALETTE[i % PALETTE.length], width: 1.4 },
    hovertemplate: `%{y:.4g} ${yUnit} at %{x:.4g} ${xUnit}<extra>${plain(s.label)}</extra>`,
    ...options(s, i),
  }));
  return { traces, xUnit, yUnit };
}

function lineLayout(data, xUnit, yUnit, traces, more = {}) {
  return {
    showlegend: traces.length > 1,
    xaxis: { title: { text: axisTitle(data.x.label, xUnit) } },
    yaxis: { title: { text: axisTitle(data.y.label, yUnit) } },
    ...more,
  };
}

function buildLines(data) {
  const { traces, xUnit, yUnit } = lineTraces(data);
  return { traces, layout: lineLayout(data, xUnit, yUnit, traces) };
}

// The energy budget: the terms stacked, what the scheme lost on top (hatched), the input dashed.
function buildEnergy(data) {
  const isInput = (s) => s.key === "input";
  const isLost = (s) => s.key === "numerical";
  const ordered = { ...data, series: [...data.series.filter((s) => !isInput(s) && !isLost(s)),
                                      ...data.series.filter(isLost), ...data.series.filter(isInput)] };
  const terms = ordered.series.filter((s) => !isInput(s)).length;
  // One box at the hovered time lists every term (the time heads it).
  const { traces, xUnit, yUnit } = lineTraces(ordered, (s, i) => {
    const hovertemplate = `%{y:.4g} ${data.y.unit}`;
    if (isInput(s)) return { hovertemplate, line: { color: "#1d2430", width: 1.6, dash: "dash" } };
    const colour = isLost(s) ? "#b0b6c0" : PALETTE[i % PALETTE.length];
    return {
      hovertemplate, stackgroup: "budget", line: { width: 0, color: colour }, fillcolor: colour,
      ...(isLost(s) ? { fillpattern: { shape: "/", fgcolor: "#b42318", size: 6, solidity: 0.15 } } : {}),
    };
  });
  const layout = lineLayout(ordered, xUnit, yUnit, traces, { hovermode: terms > 1 ? "x unified" : "closest" });
  layout.xaxis.unifiedhovertitle = { text: `t = %{x:.4g} ${xUnit}` };
  return { traces, layout };
}

// The medium's force against the penetration, the permanent penetration marked.
function buildForcePenetration(data, summary) {
  const { traces, xUnit, yUnit } = lineTraces(data);
  const permanent = summary.medium_penetration && summary.medium_penetration.permanent;
  const shapes = [], annotations = [];
  if (typeof permanent === "number") {
    const x = inUnit(permanent, xUnit);
    shapes.push({ type: "line", xref: "x", yref: "paper", x0: x, x1: x, y0: 0, y1: 1,
                  line: { color: "#b42318", width: 1, dash: "dash" } });
    annotations.push({ xref: "x", yref: "paper", x, y: 1, yanchor: "top", xanchor: "right", showarrow: false,
                       text: `permanent ${brief(x)} ${xUnit}`, font: { size: 11, color: "#b42318" } });
  }
  return { traces, layout: lineLayout(data, xUnit, yUnit, traces, { shapes, annotations }) };
}

// The fields' frame times in display units.
const fieldTimeUnit = (fields) => timeUnit(fields.times[fields.times.length - 1] || 0);

// The fields' stress and stations: the stress in its shown unit, the stations (along the tool) in metres.
const STRESS = shownUnit("stress");
const STATIONS = "m";

// Stress along the tool at frame `chart.frame`, on a stress scale fixed over every frame, so that
// the slider moves the curve, not the axis.
function buildStressAlong(fields, frame) {
  const t = fieldTimeUnit(fields);
  const bound = 1.05 * (inUnit(largestMagnitude(fields.stress), STRESS) || 1);
  const time = `${brief(inUnit(fields.times[frame], t))} ${t}`;
  return {
    traces: [{
      type: "scatter", mode: "lines", name: `t = ${time}`, x: fields.stations, y: scaled(fields.stress[frame], STRESS),
      line: { color: PALETTE[0], width: 1.6 },
      hovertemplate: `%{y:.4g} ${STRESS} at x = %{x:.4g} ${STATIONS}<extra>t = ${time}</extra>`,
    }],
    layout: {
      showlegend: false,
      xaxis: { title: { text: axisTitle(fields.x.label, STATIONS) } },
      yaxis: { title: { text: `stress σ (${STRESS})` }, range: [-bound, bound], zeroline: true, zerolinecolor: "#98a2b3" },
      annotations: [{ xref: "paper", yref: "paper", x: 1, y: 1, xanchor: "right", yanchor: "top", showarrow: false,
                      text: `t = ${time}`, font: { size: 12 } }],
    },
  };
}

// σ(x, t) over the tool and the run: time across, x up, zero white; the slider's time marked.
function buildSpacetime(fields, frame) {
  const t = fieldTimeUnit(fields);
  const bound = inUnit(largestMagnitude(fields.stress), STRESS) || 1;
  // z is a row a station: the transpose of the API's row a time.
  const z = fields.stations.map((_, j) => fields.stress.map((row) => (row[j] === null ? null : inUnit(row[j], STRESS))));
  const at = inUnit(fields.times[frame], t);
  return {
    traces: [{
      type: "heatmap", x: scaled(fields.times, t), y: fields.stations, z, zmin: -bound, zmax: bound, zmid: 0,
      colorscale: DIVERGING, colorbar: { title: { text: `σ (${STRESS})`, side: "top" }, thickness: 12, outlinewidth: 0 },
      hovertemplate: `σ = %{z:.4g} ${STRESS}<br>x = %{y:.4g} ${STATIONS}, t = %{x:.4g} ${t}<extra></extra>`,
    }],
    layout: {
      xaxis: { title: { text: axisTitle("time t", t) }, showgrid: false },
      yaxis: { title: { text: axisTitle(fields.x.label, STATIONS) }, showgrid: false },
      shapes: [{ type: "line", xref: "x", yref: "paper", x0: at, x1: at, y0: 0, y1: 1,
                 line: { color: "#1d2430", width: 1, dash: "dot" } }],
    },
  };
}

// The blows table from the summary: peak force, energy to the medium and set, blow by blow:
// [key, label, quantity].
const BLOW_BARS = [
  ["peak_contact_force", "peak contact force", "force"],
  ["to_medium", "energy to the medium", "energy"],
  ["set", "set", "length"],
];

// Panels of bars side by side, one a [key, label, quantity] of `columns`, against the blow:
// `rows[i][key]` is blow i+1's.
function buildBars(rows, columns) {
  const number = rows.map((_, i) => i + 1);
  const traces = columns.map(([key, label, quantity], k) => ({
    type: "bar", name: label, x: number, y: scaled(rows.map((b) => b[key]), shownUnit(quantity)),
    xaxis: `x${k ? k + 1 : ""}`, yaxis: `y${k ? k + 1 : ""}`, marker: { color: PALETTE[k] },
    hovertemplate: `${label} %{y:.4g} ${shownUnit(quantity)}, blow %{x}<extra></extra>`,
  }));
  const layout = { showlegend: false, grid: { rows: 1, columns: columns.length, pattern: "independent", xgap: 0.28 },
                   margin: { l: 44, r: 8, t: 24, b: 40 }, annotations: [] };
  columns.forEach(([, label, quantity], k) => {
    const n = k ? k + 1 : "";
    layout[`xaxis${n}`] = { title: { text: "blow" }, dtick: 1 };
    layout[`yaxis${n}`] = { title: { text: shownUnit(quantity) } };
    layout.annotations.push({ xref: `x${n} domain`, yref: `y${n} domain`, x: 0.5, y: 1, yanchor: "bottom",
                              showarrow: false, text: label, font: { size: 11 } });
  });
  return { traces, layout };
}

const buildBlows = (blows) => buildBars(blows, BLOW_BARS);

// The summary's stress envelope: each stretch of the tool's greatest compression and tension, as
// steps along it (a stretch the grid has no node in is left blank).
function buildEnvelope(envelope) {
  const length = shownUnit("length");
  const x = scaled(envelope.x.slice(1).flatMap((end, k) => [envelope.x[k], end]), length);
  const traces = [["compression", "greatest compression"], ["tension", "greatest tension"]].map(([key, label], k) => ({
    type: "scatter", mode: "lines", name: label, x,
    y: scaled(envelope[key].flatMap((v) => [v, v]), STRESS),
    line: { color: PALETTE[k], width: 1.8 },
    hovertemplate: `${label} %{y:.4g} ${STRESS} at x = %{x:.4g} ${length}<extra></extra>`,
  }));
  return {
    traces,
    layout: {
      xaxis: { title: { text: `x from the struck end (${length})` } },
      yaxis: { title: { text: `stress (${STRESS})` }, rangemode: "tozero" },
    },
  };
}

function envelopeCsv(envelope, stem) {
  const text = csvText(["from (m)", "to (m)", "greatest compression (Pa)", "greatest tension (Pa)"],
    envelope.compression.map((c, k) => [envelope.x[k], envelope.x[k + 1], c, envelope.tension[k]]));
  return { blob: new Blob([text], { type: "text/csv" }), name: `${stem}.csv` };
}

// A hammer at work's blows (`summary.cycle`): the impact velocity, energy and stroke of each.
const CYCLE_BARS = [
  ["impact_velocity", "impact velocity", "speed"],
  ["impact_energy", "impact energy", "energy"],
  ["stroke", "stroke", "length"],
];

// Each blow's row of CYCLE_BARS: its impact energy ½·m·v², the striker's mass m from the energy
// it brought (`energy.initial`, Σ ½·m·v² over the impacts).
function cycleRows(summary) {
  const { impact_velocity: velocity, stroke } = summary.cycle;
  const mass = (2 * summary.energy.initial) / velocity.reduce((sum, v) => sum + v * v, 0);
  return velocity.map((v, i) => ({ impact_velocity: v, impact_energy: 0.5 * mass * v * v, stroke: stroke[i] }));
}

function blowsCsv(blows, stem) {
  const columns = Object.keys(blows[0] || {});
  const text = csvText(["blow", ...columns], blows.map((b, i) => [i + 1, ...columns.map((c) => b[c])]));
  return { blob: new Blob([text], { type: "text/csv" }), name: `${stem}.csv` };
}

// ---------------------------------------------------------------------------------------------
// The "Plots" card of a job.

const seriesPath = (id, name, query = "") => `/v1/jobs/${id}/series/${name}${query}`;
const linePoints = (full) => `?points=${full ? 0 : SCREEN_POINTS}`;
const fieldPoints = (full) => (full ? "?times=0&stations=0" : `?times=${FIELD_TIMES}&stations=${FIELD_STATIONS}`);

// The charts, in the order shown: [chart name, series it draws, title, frame options].
const JOB_CHARTS = [
  ["force", "force"],
  ["displacements", "displacements"],
  ["probes", "probes"],
  ["stress_along", "fields", "Stress along the tool"],
  ["spacetime", "fields"], // the service's title for the fields: σ over x and t
  ["force_penetration", "force_penetration"],
  ["pressures", "pressures"], // a hammer at work's
  ["striker_velocity", "striker_velocity"],
  ["energy", "energy", null, { size: "tall", wide: true }], // its many terms' legend needs the width
];

export async function showCharts(view, summary) {
  const box = $("plots");
  let listed;
  try {
    ({ series: listed } = await getJSON(`/v1/jobs/${view.id}/series`));
  } catch (error) {
    const reason = error.status === 404 ? "this service does not serve the result's series" : describe(error);
    if (!view.signal.aborted) box.replaceChildren(h("p", { class: "muted" }, `No plots: ${reason}.`));
    return;
  }
  if (view.signal.aborted) return;
  const series = Object.fromEntries(listed.map((s) => [s.name, s]));
  const figures = {};
  for (const [name, source, title, options] of JOB_CHARTS) {
    if (!series[source]) continue;
    const controls = name === "stress_along" ? timeSlider() : null;
    figures[name] = chartFigure(name, title || series[source].title || name, { ...options, controls });
  }
  const blows = summary.blows && summary.blows.length ? summary.blows : null;
  if (blows) figures.blows = chartFigure("blows", "Blow by blow", { size: "short", wide: true });
  if (summary.cycle) figures.cycles = chartFigure("cycles", "Cycle by cycle", { size: "short", wide: true });
  if (summary.stress_envelope) figures.envelope = chartFigure("envelope", "Greatest stresses along the tool");
  box.replaceChildren(card("Plots", h("div", { class: "chart-grid" }, Object.values(figures))));

  const jobs = [];
  for (const [name, source] of JOB_CHARTS) {
    const figure = figures[name];
    if (!figure) continue;
    if (!series[source].available) chartUnavailable(figure, series[source].reason || "not available for this result");
  }
  const line = (name, build) => figures[name] && series[name].available && jobs.push(
    drawSeries(view, figures[name], series[name], (full) => seriesPath(view.id, name, linePoints(full)), build));
  line("force", buildLines);
  line("displacements", buildLines);
  line("probes", buildLines);
  line("energy", buildEnergy);
  line("force_penetration", (data) => buildForcePenetration(data, summary));
  line("pressures", buildLines);
  line("striker_velocity", buildLines);
  if (series.fields && series.fields.available) jobs.push(drawFields(view, figures, series.fields, summary));
  if (blows) {
    const stem = fileStem(summary.name, view.id, "blows");
    jobs.push(drawChart(figures.blows, { data: blows, build: buildBlows, file: stem, csv: async () => blowsCsv(blows, stem) }));
  }
  if (summary.stress_envelope) {
    const envelope = summary.stress_envelope;
    const stem = fileStem(summary.name, view.id, "envelope");
    jobs.push(drawChart(figures.envelope, { data: envelope, build: buildEnvelope, file: stem,
                                            csv: async () => envelopeCsv(envelope, stem) }));
  }
  if (summary.cycle) {
    const rows = cycleRows(summary);
    const stem = fileStem(summary.name, view.id, "cycles");
    jobs.push(drawChart(figures.cycles, { data: rows, build: (data) => buildBars(data, CYCLE_BARS), file: stem,
                                          csv: async () => blowsCsv(rows, stem) }));
  }
  await Promise.all(jobs);
}

// One series' chart: fetched for the screen, drawn unless the user has opened another job meanwhile.
async function drawSeries(view, figure, listed, path, build) {
  let data;
  try {
    data = await getJSON(path(false));
  } catch (error) {
    if (!view.signal.aborted) chartUnavailable(figure, `Not drawn: ${describe(error)}`);
    return;
  }
  if (view.signal.aborted) return;
  const stem = fileStem(caseName(data), view.id, listed.name);
  await drawChart(figure, {
    data, build, file: stem,
    load: async (full) => getJSON(path(full)),
    csv: async () => download(listed.links.csv, `${stem}.csv`),
  });
}

// The time slider under the stress along the tool: a frame's index, its time in words.
function timeSlider() {
  const input = h("input", { type: "range", min: 0, max: 0, step: 1, value: 0, disabled: true, class: "time-slider",
                             "aria-label": "time of the stress along the tool" });
  const output = h("output", { class: "time-value" }, "t = —");
  return h("div", { class: "chart-controls" }, h("label", {}, h("span", { class: "muted" }, "time "), input), output);
}

// Stress along the tool and its space–time map, from one fetch of the fields.
async function drawFields(view, figures, listed, summary) {
  const along = figures.stress_along, map = figures.spacetime;
  let fields;
  try {
    fields = await getJSON(seriesPath(view.id, "fields", fieldPoints(false)));
  } catch (error) {
    if (!view.signal.aborted) for (const f of [along, map]) chartUnavailable(f, `Not drawn: ${describe(error)}`);
    return;
  }
  if (view.signal.aborted) return;
  if (!fields.times.length) {
    for (const f of [along, map]) chartUnavailable(f, "the result has no frames of the stress fields");
    return;
  }
  // First shown: the frame nearest the largest compression, where the wave is worth a look.
  const peak = summary.max_compressive_stress && summary.max_compressive_stress.time;
  const frame = typeof peak === "number" ? nearestFrame(fields.times, peak) : 0;
  const t = fieldTimeUnit(fields);
  const input = along.querySelector(".time-slider");
  const output = along.querySelector(".time-value");
  const label = (i) => `t = ${brief(inUnit(fields.times[i], t))} ${t}`;
  Object.assign(input, { max: fields.times.length - 1, value: frame, disabled: false });
  input.setAttribute("aria-valuetext", label(frame));
  output.textContent = label(frame);

  const stem = (name) => fileStem(caseName(fields), view.id, name);
  const load = async (full) => getJSON(seriesPath(view.id, "fields", fieldPoints(full)));
  // An export at full resolution finds the slider's frame by its time among all the frames.
  const atTime = (data) => nearestFrame(data.times, fields.times[along.chart.frame]);
  const csv = async () => download(listed.links.csv, `${stem("fields")}.csv`);
  const alongChart = { data: fields, frame, file: stem("stress_along"), load, csv,
                       build: (data) => buildStressAlong(data, data === fields ? alongChart.frame : atTime(data)) };
  const mapChart = { data: fields, file: stem("spacetime"), load, csv,
                     build: (data) => buildSpacetime(data, data === fields ? alongChart.frame : atTime(data)) };
  input.addEventListener("input", () => {
    alongChart.frame = Number(input.value);
    input.setAttribute("aria-valuetext", label(alongChart.frame));
    output.textContent = label(alongChart.frame);
    drawChart(along, alongChart);
    const x = inUnit(fields.times[alongChart.frame], t);
    Plotly.relayout(plotArea(map), { "shapes[0].x0": x, "shapes[0].x1": x });
  });
  await Promise.all([drawChart(along, alongChart), drawChart(map, mapChart)]);
}

function nearestFrame(times, t) {
  let best = 0;
  times.forEach((s, i) => { if (Math.abs(s - t) < Math.abs(times[best] - t)) best = i; });
  return best;
}
