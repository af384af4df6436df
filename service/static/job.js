// One job on view: polled until it finishes, then its summary and charts, or a study's answer.
import { api, describe, download, getJSON, objectUrl } from "./api.js";
import { showCharts } from "./charts.js";
import { $, clock, h, save, seconds } from "./dom.js";
import { loadCase } from "./editor.js";
import { refreshJobs } from "./jobs.js";
import { poll } from "./poll.js";
import { showSignalMatch } from "./matching.js";
import { PILE_STUDIES, showPileStudy } from "./piling.js";
import { showStudy } from "./studies.js";
import { summaryCards } from "./summary.js";
import { inUnit } from "./units.js";
import { showView } from "./view.js";

const POLL_MS = 250;
const FINISHED = ["succeeded", "failed", "cancelled"];

let shown = null; // the job last opened: {id, signal, urls}; its signal aborts when another view opens

// The job on view, if a job is.
export const shownJob = () => (shown && !shown.signal.aborted ? shown : null);

// A calibration, an optimisation, a pile study or a signal match: a job whose answer is not a run's result.
export const isStudy = (job) => Boolean(job.kind) && job.kind !== "run";

export async function openJob(id) {
  const view = { id, signal: showView("job", `#job=${id}`), urls: [] };
  view.signal.addEventListener("abort", () => view.urls.forEach((url) => URL.revokeObjectURL(url)));
  shown = view;
  document.querySelectorAll(".job-link").forEach((b) =>
    b.toggleAttribute("aria-current", b.dataset.job === id));
  $("job-title").textContent = id;
  $("job-error").hidden = true;
  $("summary").replaceChildren();
  $("study").replaceChildren();
  $("plots").replaceChildren();
  const job = await poll(`/v1/jobs/${id}`, {
    signal: view.signal, every: POLL_MS, done: (answer) => FINISHED.includes(answer.status), update: renderJob,
    failed: (error) => showJobError(describe(error)),
  });
  if (!job) return;
  refreshJobs();
  if (job.status === "failed") showJobError(job.error || "the job failed without a reason");
  if (job.status === "succeeded" && job.kind in PILE_STUDIES) {
    await showPileStudy(view, job.kind);
  } else if (job.status === "succeeded" && job.kind === "signal_match") {
    await showSignalMatch(view);
  } else if (job.status === "succeeded" && isStudy(job)) {
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
    ran !== null && (ran < 1 ? `ran ${+inUnit(ran, "ms").toPrecision(3)} ms` : `ran ${+ran.toPrecision(3)} s`),
    job.worker && `on ${job.worker}`,
  ].filter(Boolean).join(" · ");
}

export function showJobError(message) {
  const box = $("job-error");
  box.textContent = message;
  box.hidden = false;
}

export async function cancelJob() {
  try {
    // POST …/cancel, not DELETE: a job that finished meanwhile is kept, not removed.
    await api(`/v1/jobs/${shown.id}/cancel`, { method: "POST" });
  } catch (error) {
    // 409: it finished meanwhile, which the next poll shows.
    if (error.status !== 409) showJobError(`Cancel failed: ${describe(error)}`);
  }
}

export async function editCase() {
  try {
    loadCase(await getJSON(`/v1/jobs/${shown.id}/case`));
  } catch (error) {
    showJobError(`The case could not be loaded: ${describe(error)}`);
  }
}

export async function downloadResult() {
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

async function showSummary(view) {
  let s;
  try {
    s = await getJSON(`/v1/jobs/${view.id}/summary`);
  } catch (error) {
    if (!view.signal.aborted) showJobError(`The summary could not be loaded: ${describe(error)}`);
    return null;
  }
  if (view.signal.aborted) return null;
  $("summary").replaceChildren(...summaryCards(s));
  return s;
}

// ---------------------------------------------------------------------------------------------
// A study's plot, drawn by the service: its PNG, a click opens the SVG full size.

// The plot's PNG in `frame`, fetched with the key; a click enlarges it.
export async function showImage(frame, plot, view) {
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
