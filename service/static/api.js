// The API: every call carries the key, and a 401 anywhere asks the user for one.
import { $ } from "./dom.js";

export const KEY_STORAGE = "percussim.apiKey";

export class ApiError extends Error {
  constructor(status, detail, retryAfter) {
    super(typeof detail === "string" ? detail : `the service answered ${status}`);
    this.status = status;
    this.detail = detail;
    this.retryAfter = retryAfter;
  }
}

// `askKey: false`: a 401 is only thrown, not asked about (a check while the user types must not
// take the focus from the field).
export async function api(path, { askKey = true, ...options } = {}) {
  const headers = new Headers(options.headers || {});
  const key = localStorage.getItem(KEY_STORAGE);
  if (key) headers.set("X-API-Key", key);
  const response = await fetch(path, { ...options, headers });
  if (response.ok) return response;
  const text = await response.text();
  let detail = text;
  try { detail = JSON.parse(text).detail ?? text; } catch { /* a plain-text answer */ }
  if (response.status === 401 && askKey) askForKey(detail);
  throw new ApiError(response.status, detail, response.headers.get("Retry-After"));
}

export const getJSON = async (path, options) => (await api(path, options)).json();

export function describe(error) {
  if (!(error instanceof ApiError)) return `the service could not be reached (${error.message})`;
  if (error.status === 401) return "an API key is needed";
  const retry = error.retryAfter ? ` Try again in ${error.retryAfter} s.` : "";
  return `${error.message}${retry}`;
}

// What went wrong, in words: the service's answer, or the browser's (a fetch, a drawing).
export const failure = (error) => (error instanceof ApiError ? describe(error) : error.message);

// A blob fetched with the key, as an object URL: an <img> or a link cannot send the header.
export async function objectUrl(path, urls) {
  const url = URL.createObjectURL(await (await api(path)).blob());
  urls.push(url);
  return url;
}

// A file fetched with the key, named as the service names it (or `fallback`).
export async function download(path, fallback) {
  const response = await api(path);
  const disposition = response.headers.get("Content-Disposition") || "";
  const match = /filename\*=utf-8''([^;]+)/i.exec(disposition) || /filename="?([^";]+)"?/i.exec(disposition);
  return { blob: await response.blob(), name: match ? decodeURIComponent(match[1]) : fallback };
}

function askForKey(detail) {
  const banner = $("key-needed");
  const reason = typeof detail === "string" && detail ? detail : "this service needs an API key";
  banner.textContent = `${reason[0].toUpperCase()}${reason.slice(1)}: enter a key above and press Save.`;
  banner.hidden = false;
  $("api-key").classList.add("attention");
  $("api-key").focus();
}
