// The case: a preset or pasted JSON in the case editor (#case-json), checked for syntax here and
// for meaning by the service; and the forms' way of sending what they make.
import { describe, getJSON } from "./api.js";
import { $, h, showProblems } from "./dom.js";
import { showFieldProblems } from "./form.js";
import { openJob } from "./job.js";
import { refreshJobs } from "./jobs.js";

export async function loadPresets() {
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

export async function choosePreset() {
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

// A case (a job's, a fitted or best one) into the form and the JSON view, to change and run again.
export function loadCase(caseJson) {
  setCaseText(JSON.stringify(caseJson, null, 2));
  $("case-fields").scrollIntoView({ block: "start" });
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
export function editedCase(box) {
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
export async function send(path, body, { button, box, what, where = (field) => field,
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

export async function submitCase(event) {
  event.preventDefault();
  const box = $("case-errors");
  // The text as typed: the service reads it and names what is wrong.
  if (editedCase(box)) {
    await send("/v1/jobs", $("case-json").value, { button: $("submit"), box, what: "case", refused: showFieldProblems });
  }
}
