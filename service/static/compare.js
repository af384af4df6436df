// Two to eight finished jobs side by side: their contact force and probe stresses overlaid, their
// summaries in one table with what differs from the first (the reference) highlighted, and the
// case fields that differ.
import { describe, failure, getJSON } from "./api.js";
import {
  axisTitle, chartFigure, chartUnavailable, csvText, displayUnit, drawChart, largest, PALETTE, plain, scaled,
  SCREEN_POINTS,
} from "./charts.js";
import { $, card, fmt, h, table } from "./dom.js";
import { openJob } from "./job.js";
import { COMPARE_MAX, COMPARE_MIN } from "./jobs.js";
import { PULSE, pulseValue } from "./summary.js";
import { shownUnit } from "./units.js";
import { showView } from "./view.js";

const AGREEMENT = 0.005; // relative difference taken as real when neither job estimates its error

const shortId = (id) => id.slice(0, 6);
const jobLabel = (job) => `${(job.record && job.record.name) || "(unnamed)"} · ${shortId(job.id)}`;

export async function openComparison(ids) {
  ids = [...new Set(ids.filter(Boolean))];
  // One opened later replaces this one, which then stops drawing.
  const signal = showView("comparison", `#compare=${ids.join(",")}`);
  const box = $("comparison");
  const live = () => !signal.aborted;
  if (ids.length < COMPARE_MIN || ids.length > COMPARE_MAX) {
    box.replaceChildren(h("h2", {}, "Comparison"), h("p", { class: "banner error" },
      `Pick between ${COMPARE_MIN} and ${COMPARE_MAX} jobs to compare; ${ids.length} ${ids.length === 1 ? "was" : "were"} picked.`));
    return;
  }

  // The frames first, at their size, so the page does not move as the jobs arrive.
  const station = h("select", { class: "probe-station", disabled: true });
  const forceFigure = chartFigure("compare-force", "Contact force");
  const probesFigure = chartFigure("compare-probes", "Stress at a probe", {
    controls: h("div", { class: "chart-controls" }, h("label", {}, h("span", { class: "muted" }, "probe at"), station)),
  });
  const jobsList = h("ul", { class: "compare-jobs" }, ids.map((id) => h("li", {}, h("span", { class: "muted" }, id))));
  const summaries = h("div", { class: "compare-summaries" }, h("p", { class: "muted" }, "Loading the jobs…"));
  const cases = h("div", { class: "compare-cases" });
  box.replaceChildren(
    h("h2", {}, "Comparison ", h("span", { class: "muted small" }, `${ids.length} jobs`)),
    jobsList,
    card("Contact force and probe stresses", h("div", { class: "chart-grid" }, forceFigure, probesFigure)),
    card("Summaries", summaries),
    cases);

  const jobs = await Promise.all(ids.map(loadCompared));
  if (!live()) return;
  const ready = jobs.filter((job) => job.summary);
  ready.forEach((job, i) => { job.colour = PALETTE[i % PALETTE.length]; });
  jobsList.replaceChildren(...jobs.map(jobItem));
  if (ready.length < COMPARE_MIN) {
    const reason = `Fewer than ${COMPARE_MIN} of these jobs have succeeded: nothing to compare.`;
    for (const figure of [forceFigure, probesFigure]) chartUnavailable(figure, reason);
    summaries.replaceChildren(h("p", { class: "muted" }, reason));
    return;
  }
  summaries.replaceChildren(summaryTable(ready));
  const stem = (name) => `compare-${ready.map((job) => shortId(job.id)).join("-")}-${name}`;
  await Promise.all([
    drawCompareForce(forceFigure, ready, stem("force"), live),
    drawCompareProbes(probesFigure, station, ready, stem("probes"), live),
    showCaseDifferences(cases, ready, live),
  ]);
}

// A job's record, and when it has succeeded its summary and its force and probe series (for the
// screen); what could not be fetched is said in `problem`.
async function loadCompared(id) {
  const job = { id, record: null, summary: null, series: {}, problem: null };
  try {
    job.record = await getJSON(`/v1/jobs/${id}`);
  } catch (error) {
    job.problem = describe(error);
    return job;
  }
  if (job.record.status !== "succeeded") return job;
  if (job.record.kind && job.record.kind !== "run") {
    job.problem = `a ${job.record.kind}, not a run`;
    return job;
  }
  // Only the series the result has: one it lacks (no probes) is left out, not asked for and refused.
  const listed = getJSON(`/v1/jobs/${id}/series`).then(({ series }) => series, (error) => ({ error }));
  const series = async (name) => {
    const all = await listed;
    if (all.error) return all;
    const one = all.find((s) => s.name === name);
    if (!one || !one.available) return { error: new Error((one && one.reason) || `no ${name} series`) };
    return getJSON(`${one.links.json}?points=${SCREEN_POINTS}`).catch((error) => ({ error }));
  };
  try {
    [job.summary, job.series.force, job.series.probes] = await Promise.all([
      getJSON(`/v1/jobs/${id}/summary`), series("force"), series("probes")]);
  } catch (error) {
    job.problem = `its summary could not be loaded: ${describe(error)}`;
  }
  return job;
}

function jobItem(job) {
  const status = job.record ? job.record.status : "unknown";
  const left = !job.summary;
  return h("li", { "data-job": job.id, class: left ? "left-out" : null },
    job.colour ? h("span", { class: "swatch", style: `background: ${job.colour}` }) : null,
    h("button", { type: "button", class: "link", onclick: () => openJob(job.id) }, jobLabel(job)), " ",
    h("span", { class: `badge ${status}` }, status),
    left ? h("span", { class: "muted" }, ` left out${job.problem ? `: ${job.problem}` : ""}`) : null);
}

// ---------------------------------------------------------------------------------------------
// The charts: one trace a job, in the job's colour.

// The series `name` of each job, at full resolution for an export or those already fetched.
async function comparedSeries(jobs, name, full) {
  if (!full) return jobs.map((job) => job.series[name]);
  return Promise.all(jobs.map((job) => (job.series[name] && !job.series[name].error
    ? getJSON(`/v1/jobs/${job.id}/series/${name}?points=0`) : job.series[name])));
}

// One trace a job: the line of its series that `pick` chooses.
function overlay(jobs, all, pick) {
  const drawn = jobs.map((job, i) => [job, all[i] && !all[i].error ? pick(all[i]) : null, all[i]]).filter(([, line]) => line);
  if (!drawn.length) return null;
  const first = drawn[0][2];
  const xUnit = displayUnit(first.x, largest(drawn.map(([, line]) => line.x)));
  const yUnit = displayUnit(first.y, 0);
  return {
    traces: drawn.map(([job, line]) => ({
      type: "scatter", mode: "lines", name: plain(jobLabel(job)), x: scaled(line.x, xUnit),
      y: scaled(line.y, yUnit), line: { color: job.colour, width: 1.4 },
      hovertemplate: `%{y:.4g} ${yUnit} at %{x:.4g} ${xUnit}<extra>${plain(jobLabel(job))}</extra>`,
    })),
    layout: {
      showlegend: true,
      xaxis: { title: { text: axisTitle(first.x.label, xUnit) } },
      yaxis: { title: { text: axisTitle(first.y.label, yUnit) } },
    },
    drawn,
  };
}

// The lines overlaid as CSV, every job's samples one after another (their times differ).
function overlayCsv(jobs, all, pick, name, extra = []) {
  const chart = overlay(jobs, all, pick);
  if (!chart) throw new Error("no job has this series");
  const [, , first] = chart.drawn[0];
  const header = ["job", "name", ...extra.map(([column]) => column),
                  `${first.x.label} (${first.x.unit})`, `${first.y.label} (${first.y.unit})`];
  const rows = [];
  for (const [job, line] of chart.drawn) {
    const before = [job.id, job.record.name || "", ...extra.map(([, value]) => value)];
    line.x.forEach((x, k) => rows.push([...before, x, line.y[k]]));
  }
  return { blob: new Blob([csvText(header, rows)], { type: "text/csv" }), name: `${name}.csv` };
}

const contactLine = (data) => data.series.find((s) => s.key === "contact_force") || data.series[0];

async function drawCompareForce(figure, jobs, stem, live) {
  const all = await comparedSeries(jobs, "force", false);
  if (!live()) return;
  const build = (data) => overlay(jobs, data, contactLine);
  if (!build(all)) {
    chartUnavailable(figure, `Not drawn: ${all.map((s) => s && s.error && failure(s.error)).find(Boolean) || "no series"}`);
    return;
  }
  await drawChart(figure, {
    data: all, build, file: stem,
    load: (full) => comparedSeries(jobs, "force", full),
    csv: async () => overlayCsv(jobs, await comparedSeries(jobs, "force", true), contactLine, stem),
  });
}

// The probe stations of every job, by their label ("x = 0.01 m"), in order; the first chosen is
// one that every job has, if any.
function stations(all) {
  const labels = [];
  for (const data of all) {
    if (!data || data.error) continue;
    for (const s of data.series) if (!labels.includes(s.label)) labels.push(s.label);
  }
  const everywhere = labels.filter((label) => all.every((d) => d && !d.error && d.series.some((s) => s.label === label)));
  return { labels, first: everywhere[0] || labels[0] };
}

async function drawCompareProbes(figure, select, jobs, stem, live) {
  const all = await comparedSeries(jobs, "probes", false);
  if (!live()) return;
  const { labels, first } = stations(all);
  if (!labels.length) {
    chartUnavailable(figure, "None of these jobs has probes: run a case with outputs.probes, the stations x (m) along the tool.");
    return;
  }
  select.replaceChildren(...labels.map((label) => {
    const count = all.filter((d) => d && !d.error && d.series.some((s) => s.label === label)).length;
    return h("option", { value: label, selected: label === first },
      count === jobs.length ? label : `${label} (${count} of ${jobs.length} jobs)`);
  }));
  select.disabled = false;
  const pick = (data) => data.series.find((s) => s.label === select.value);
  const chart = {
    data: all, file: stem,
    build: (data) => overlay(jobs, data, pick) || { traces: [], layout: {} },
    load: (full) => comparedSeries(jobs, "probes", full),
    csv: async () => overlayCsv(jobs, await comparedSeries(jobs, "probes", true), pick, `${stem}`,
                                [["probe", select.value]]),
  };
  select.addEventListener("change", () => drawChart(figure, chart));
  await drawChart(figure, chart);
}

// ---------------------------------------------------------------------------------------------
// The summaries side by side.

// A quantity's estimated relative error in `summary`, or null.
function estimated(summary, quantity) {
  const value = (summary.error_estimate || {})[quantity];
  return typeof value === "number" ? value : null;
}

// How far `value` is from the reference's, and whether that is more than either job's estimated
// error (or AGREEMENT when neither has one).
function difference(value, reference, errors) {
  if (value === reference) return { differs: false, text: "" };
  if (value === null || reference === null) return { differs: true, text: "" };
  if (reference === 0) return { differs: true, text: "from 0" };
  const relative = (value - reference) / Math.abs(reference);
  const known = errors.filter((e) => e !== null);
  const allowed = known.length ? Math.max(...known) : AGREEMENT;
  const percent = Math.abs(100 * relative);
  const digits = percent < 0.1 ? percent.toPrecision(2) : percent.toFixed(1);
  return { differs: Math.abs(relative) > allowed, text: `${relative < 0 ? "−" : "+"}${digits}%` };
}

function summaryTable(jobs) {
  const [reference] = jobs;
  const rows = PULSE.filter((q) => jobs.some((job) => pulseValue(q, job.summary) !== null))
    .map((q) => {
      const { label, key, quantity } = q;
      const base = pulseValue(q, reference.summary);
      return h("tr", { "data-quantity": key },
        h("th", {}, label, h("span", { class: "unit" }, shownUnit(quantity))),
        jobs.map((job, i) => {
          const v = pulseValue(q, job.summary);
          const diff = i === 0 ? { differs: false, text: "" }
            : difference(v, base, [estimated(job.summary, key), estimated(reference.summary, key)]);
          return h("td", { class: diff.differs ? "num value differs" : "num value", "data-job": job.id,
                           title: diff.differs ? "differs from the reference by more than the estimated errors" : null },
            h("span", { class: "number" }, fmt(v)), diff.text ? h("span", { class: "diff" }, diff.text) : null);
        }));
    });
  const worst = (job) => {
    const e = job.summary.error_estimate;
    return e && typeof e.worst === "number" ? `±${fmt(100 * e.worst, 2)}%` : "n/a";
  };
  rows.push(h("tr", { "data-quantity": "error_estimate.worst" },
    h("th", {}, "Estimated error (worst)"),
    jobs.map((job) => h("td", { class: "num", "data-job": job.id }, worst(job)))));
  const head = jobs.map((job, i) => h("th", { class: i === 0 ? "compare-head reference" : "compare-head", scope: "col" },
    h("button", { type: "button", title: "open this job", onclick: () => openJob(job.id) },
      h("span", { class: "swatch", style: `background: ${job.colour}` }), job.record.name || "(unnamed)",
      h("span", { class: "id" }, shortId(job.id)), i === 0 ? h("span", { class: "reference" }, "reference") : null)));
  return h("div", {},
    h("table", { class: "compare" },
      h("thead", {}, h("tr", {}, h("th", {}, ""), head)),
      h("tbody", {}, rows)),
    h("p", { class: "muted small compare-note" },
      "Highlighted: differs from the first job by more than the larger of the two jobs' estimated errors ",
      `(${100 * AGREEMENT}% when neither has one).`));
}

// ---------------------------------------------------------------------------------------------
// The case fields that differ.

// A case as {path: value as text}; lists are one value.
function flatten(value, prefix = "", out = {}) {
  if (value && typeof value === "object" && !Array.isArray(value)) {
    for (const [key, inner] of Object.entries(value)) flatten(inner, prefix ? `${prefix}.${key}` : key, out);
  } else {
    // a text as it is; numbers, lists and booleans as JSON, exactly as the case has them
    out[prefix] = typeof value === "string" ? value : JSON.stringify(value);
  }
  return out;
}

async function showCaseDifferences(box, jobs, live) {
  const cases = await Promise.all(jobs.map((job) => getJSON(`/v1/jobs/${job.id}/case`).catch((error) => ({ error }))));
  if (!live()) return;
  const missing = cases.find((c) => c.error);
  if (missing) {
    box.replaceChildren(card("Case fields that differ", h("p", { class: "muted" }, `Not compared: ${describe(missing.error)}.`)));
    return;
  }
  const flat = cases.map((c) => flatten(c));
  const paths = [];
  for (const f of flat) for (const path of Object.keys(f)) if (!paths.includes(path)) paths.push(path);
  const differing = paths.filter((path) => path !== "description" && new Set(flat.map((f) => f[path])).size > 1);
  const shownValue = (text) => (text === undefined ? "—" : text);
  const content = differing.length
    ? table("case-diff", ["field", ...jobs.map(jobLabel)], differing.map((path) => h("tr", { "data-field": path },
        h("th", {}, path),
        flat.map((f, i) => h("td", { class: i > 0 && f[path] !== flat[0][path] ? "differs" : null }, shownValue(f[path]))))))
    : h("p", { class: "muted" }, "The cases are the same.");
  box.replaceChildren(card("Case fields that differ", content));
}
