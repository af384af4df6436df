// The page's small helpers: elements built safely, numbers and times in words, cards, tables and
// boxes of problems, and files handed to the browser.

export const $ = (id) => document.getElementById(id);

// An element with attributes and children; strings become text nodes, so nothing from the
// service is ever parsed as HTML.
export function h(tag, attrs = {}, ...children) {
  const el = document.createElement(tag);
  for (const [name, value] of Object.entries(attrs)) {
    if (value === null || value === undefined || value === false) continue;
    if (name.startsWith("on")) el.addEventListener(name.slice(2), value);
    else el.setAttribute(name, value);
  }
  el.append(...children.flat(Infinity).filter((c) => c !== null && c !== undefined && c !== false));
  return el;
}

// `digits` significant digits: 484.0, 179.9, 12345, 0.9335; an exponent only below 0.001
// (4.682e-13) and from a million up (8.014e+11), where fixed decimals would run off the table
// or bury the digits that count.
export function fmt(value, digits = 4) {
  if (typeof value !== "number" || !Number.isFinite(value)) return "—";
  if (value === 0) return "0";
  if (Math.abs(value) < 1e-3 || Math.abs(value) >= 1e6) return value.toExponential(digits - 1);
  const decimals = digits - 1 - Math.floor(Math.log10(Math.abs(value)));
  return value.toFixed(Math.max(decimals, 0));
}

// A number as typed, or the text itself when it is not one, for the service to name.
export function typed(text) {
  const value = Number(text);
  return text !== "" && Number.isFinite(value) ? value : text;
}

export const clock = (iso) => (iso ? new Date(iso).toLocaleTimeString("en-GB") : "");

export function seconds(fromIso, toIso) {
  return fromIso && toIso ? (new Date(toIso) - new Date(fromIso)) / 1000 : null;
}

export function table(className, head, rows) {
  return h("table", { class: className },
    h("thead", {}, h("tr", {}, head.map((cell) => h("th", {}, cell)))),
    h("tbody", {}, rows));
}

export function card(title, ...content) {
  return h("section", { class: "card" }, h("h3", {}, title), ...content);
}

// A box of problems under a form: a title, then a table of each field (or place) and its problem;
// `title` null empties and hides it.
export function showProblems(box, title, problems = [], where = "field") {
  box.hidden = !title;
  box.replaceChildren();
  if (!title) return;
  box.append(h("p", { class: "title" }, title));
  if (problems.length) {
    box.append(h("table", { class: "problems" },
      h("thead", {}, h("tr", {}, h("th", {}, where), h("th", {}, "problem"))),
      h("tbody", {}, problems.map((p) =>
        h("tr", {}, h("td", { class: "field" }, p.field), h("td", { class: "message" }, p.message))))));
  }
}

// Hand `blob` to the browser as a download named `name`.
export function save(blob, name) {
  const url = URL.createObjectURL(blob);
  const link = h("a", { href: url, download: name });
  document.body.append(link);
  link.click();
  link.remove();
  setTimeout(() => URL.revokeObjectURL(url), 60_000); // once the browser has taken the file
}
