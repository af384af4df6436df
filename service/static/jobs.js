// Recent jobs, each finished run with a box to pick it for a comparison.
import { describe, getJSON } from "./api.js";
import { $, clock, h } from "./dom.js";
import { isStudy, openJob, shownJob } from "./job.js";

const RECENT = 12;
export const COMPARE_MIN = 2;
export const COMPARE_MAX = 8;
export const picked = new Set(); // the jobs ticked for a comparison, kept across refreshes

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

export async function refreshJobs() {
  try {
    const { jobs } = await getJSON(`/v1/jobs?limit=${RECENT}`);
    const current = shownJob();
    $("jobs").replaceChildren(...jobs.map((job) => h("li", {},
      pickBox(job),
      h("button", { type: "button", class: "job-link", "data-job": job.id,
                    "aria-current": current && current.id === job.id ? "true" : null,
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
