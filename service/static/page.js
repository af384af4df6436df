// The job page's entry: the key, the buttons of the page's frame, and the view the address links to.
// The modules: dom.js and api.js (helpers, the API with its key), units.js (the one table of
// quantities and units), poll.js (the one poll loop), view.js (the right-hand panel's one view),
// editor.js (the case JSON), form.js with schema.js (the case form, from the case's JSON schema),
// jobs.js (recent jobs), job.js and summary.js (a job), charts.js, compare.js, sweep.js, studies.js,
// piling.js (the bearing graph and the drivability), matching.js (signal matching), records.js (a
// measured record chosen on disk).
import { KEY_STORAGE } from "./api.js";
import { openComparison } from "./compare.js";
import { $ } from "./dom.js";
import { choosePreset, loadPresets, submitCase } from "./editor.js";
import { buildForm } from "./form.js";
import { cancelJob, downloadResult, editCase, openJob, shownJob } from "./job.js";
import { picked, refreshJobs } from "./jobs.js";
import { startMatching } from "./matching.js";
import { startPiling } from "./piling.js";
import { startStudies } from "./studies.js";
import { openSweep, startSweeps } from "./sweep.js";

function saveKey(event) {
  event.preventDefault();
  const key = $("api-key").value.trim();
  if (key) localStorage.setItem(KEY_STORAGE, key);
  else localStorage.removeItem(KEY_STORAGE);
  $("key-needed").hidden = true;
  $("api-key").classList.remove("attention");
  loadPresets();
  refreshJobs();
  const job = shownJob();
  if (job) openJob(job.id);
}

// A module runs once the document is parsed, so the page's elements are all there.
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
buildForm();
startSweeps();
startStudies();
startPiling();
startMatching();
loadPresets();
refreshJobs();
const [, view, target] = /^#(job|compare|sweep)=([\w,-]+)$/.exec(location.hash) || [];
if (view === "job") openJob(target);
if (view === "compare") openComparison(target.split(","));
if (view === "sweep") openSweep(target);
