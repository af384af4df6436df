// The one poll loop of the page: a job, a sweep, whatever the service answers for until it is done.
import { ApiError, getJSON } from "./api.js";

// `ms` of waiting, cut short when `signal` aborts.
const pause = (ms, signal) => new Promise((resolve) => {
  const timer = setTimeout(resolve, ms);
  signal.addEventListener("abort", () => { clearTimeout(timer); resolve(); }, { once: true });
});

// GET `path` every `every` ms, each answer to `update`, until `done(answer)`: that answer is
// returned. A failure goes to `failed`; a lost connection (or a 5xx) may pass, so it is asked
// again after 4 × `every`, while a 4xx (a missing job, no key) will not. null when `signal`
// aborts (the view was replaced) or on a failure that stays.
export async function poll(path, { signal, every, done, update, failed }) {
  while (!signal.aborted) {
    let answer;
    try {
      answer = await getJSON(path, { signal });
    } catch (error) {
      if (signal.aborted) break;
      failed(error);
      if (error instanceof ApiError && error.status < 500) break;
      await pause(4 * every, signal);
      continue;
    }
    if (signal.aborted) break;
    update(answer);
    if (done(answer)) return answer;
    await pause(every, signal);
  }
  return null;
}
