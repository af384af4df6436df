// The right-hand panel shows one view: a job, a comparison or a sweep; `hash` links to it.
import { $ } from "./dom.js";

const VIEWS = ["job", "comparison", "sweep-view"];
let current = null; // the controller of the view on show

// Shows view `name` and returns its signal, aborted when another view replaces it: its polling
// stops, and what it was still fetching is not drawn.
export function showView(name, hash) {
  if (current) current.abort();
  current = new AbortController();
  history.replaceState(null, "", hash);
  $("no-job").hidden = true;
  for (const view of VIEWS) $(view).hidden = view !== name;
  // One column: the view is above the form (page.css), but the form's Run button is far below it.
  if (matchMedia("(max-width: 900px)").matches) $("job-panel").scrollIntoView({ block: "start" });
  return current.signal;
}
