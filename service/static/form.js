// The case form: a labelled input for every field of the case, with its unit and the paper's
// symbol; a profile editor; a drawing of the striker, tool and medium to scale; the service's own
// check as the user types. The case JSON (#case-json) stays the one source of truth: the form
// reads it on each "input" event of the textarea and rewrites it on each edit of its own.
// The fields, their kinds, labels, quantities, symbols, bounds, choices and defaults are the case's
// JSON schema's (schema.js); what is here is how they are laid out and what the choices do.
import { ApiError, describe, getJSON } from "./api.js";
import { $, h, showProblems } from "./dom.js";
import { caseFields } from "./schema.js";
import { fromSI, inUnit, reexpressed, toSI, unitsOf } from "./units.js";

// The service's problems (a 422's detail: [{field, message}]) next to the fields they concern;
// returns those that have no field on view. [] clears the marks.
export function showFieldProblems(problems) {
  return placeProblems(Array.isArray(problems) ? problems : []);
}

const CHECK_DELAY_MS = 300;
const DRAWING_HEIGHT = 156;
const UNIT_STORAGE = "percussim.units";

// Optional groups that go when their last field is emptied: an empty one would be refused
// (blows without a count) or say nothing. (A medium, a force and an anvil go by their choice.)
const PRUNED = new Set(["blows", "outputs"]);
// The fields of a fixed grid: the first three ask for one; the accuracy choice puts them aside.
const GRID_KEYS = ["cells", "time_step", "scheme", "gamma", "sigma"];

const isObject = (v) => v !== null && typeof v === "object" && !Array.isArray(v);
const obj = (v) => (isObject(v) ? v : {});
const positive = (v) => (typeof v === "number" && Number.isFinite(v) && v > 0 ? v : null);
const finite = (v) => typeof v === "number" && Number.isFinite(v);
const round = (v, digits = 6) => Number(v.toPrecision(digits)); // a derived value, not noise digits
const same = (a, b) => JSON.stringify(a ?? null) === JSON.stringify(b ?? null);

let schema = new Map(); // the case's fields and groups by path (schema.js)
let current = {}; // the case the form shows: the textarea's last text that parsed as an object
let stale = false; // the textarea holds text that does not parse
let stash = {}; // what a choice put aside (the lumped mass while the striker is a rod), to restore
const ui = { mode: {}, units: {}, diameters: {} };
const fields = []; // {f, wrap, input, unit, line}
const modes = []; // {m, wrap, input, line}
const tables = {}; // "tool.profile", "striker.profile", "outputs.probes": station tables
const targets = new Map(); // a field path -> where its problems are shown
const groups = []; // {details, count, digest, g}

// ------------------------------------------------------------------------------------------
// Paths in the case.

function getPath(c, path) {
  return path.split(".").reduce((o, key) => (isObject(o) ? o[key] : undefined), c);
}

// The order the keys of the group at `parentPath` are written in, the schema's (a medium's fields
// as its kind lists them), so that a field added by the form lands where a reader expects it
// rather than at the end of the JSON.
function orderOf(parentPath, o) {
  const group = schema.get(parentPath);
  if (!group || group.kind !== "group") return [];
  const kind = group.kinds && group.kinds[o.kind];
  return kind ? ["kind", ...kind, ...group.keys] : group.keys;
}

// `value` as `o[key]`, a new key placed in the schema's order.
function place(o, key, value, parentPath) {
  const order = orderOf(parentPath, o);
  const rank = order.indexOf(key);
  const after = Object.keys(o).find((k) => order.indexOf(k) > rank);
  if (key in o || rank < 0 || after === undefined) {
    o[key] = value;
    return;
  }
  const entries = Object.entries(o);
  for (const k of Object.keys(o)) delete o[k];
  for (const [k, v] of entries) {
    if (k === after) o[key] = value;
    o[k] = v;
  }
}

// An object at `path`, made (or replacing a non-object) when missing.
function ensure(c, path) {
  const keys = path.split(".");
  let o = c;
  keys.forEach((key, i) => {
    if (!isObject(o[key])) place(o, key, {}, keys.slice(0, i).join("."));
    o = o[key];
  });
  return o;
}

// Set `path` to `value`; undefined removes it (an emptied field: the service then applies its
// default, or says the field is required).
function setPath(c, path, value) {
  const keys = path.split(".");
  const last = keys.pop();
  if (value === undefined) {
    const parent = keys.length ? getPath(c, keys.join(".")) : c;
    if (!isObject(parent)) return;
    delete parent[last];
    for (let i = keys.length; i > 0; i--) {
      const o = getPath(c, keys.slice(0, i).join("."));
      if (!PRUNED.has(keys.slice(0, i).join(".")) || Object.keys(o).length) break;
      delete (i > 1 ? getPath(c, keys.slice(0, i - 1).join(".")) : c)[keys[i - 1]];
    }
    return;
  }
  place(keys.length ? ensure(c, keys.join(".")) : c, last, value, keys.join("."));
}

// A profile's last station is its rod's length: typing the length moves it.
const lastStation = (rod) => (c, length) => {
  const x = getPath(c, `${rod}.profile.x`);
  if (Array.isArray(x) && x.length >= 2 && positive(length)) x[x.length - 1] = length;
};

const pick = (o, keys) => Object.fromEntries(keys.filter((k) => o[k] !== undefined).map((k) => [k, o[k]]));
const restore = (key, fallback) => (stash[key] && Object.keys(stash[key]).length ? stash[key] : fallback);

// ------------------------------------------------------------------------------------------
// Geometry of a rod (the tool, an elastic striker): what the drawing and the choices use.

// Its stations [[x, area], ...] where the case gives them as numbers, in order; null if fewer
// than two.
function stations(rod) {
  const r = obj(rod);
  if (isObject(r.profile)) {
    const { x, area } = r.profile;
    if (!Array.isArray(x) || !Array.isArray(area)) return null;
    const pairs = [];
    for (let i = 0; i < Math.min(x.length, area.length); i++) {
      if (finite(x[i]) && x[i] >= 0 && positive(area[i]) && (!pairs.length || x[i] > pairs.at(-1)[0])) {
        pairs.push([x[i], area[i]]);
      }
    }
    return pairs.length >= 2 ? pairs : null;
  }
  const length = positive(r.length);
  return length && positive(r.area) ? [[0, r.area], [length, r.area]] : null;
}

function volume(pairs) {
  let v = 0;
  for (let i = 1; i < pairs.length; i++) v += ((pairs[i][1] + pairs[i - 1][1]) / 2) * (pairs[i][0] - pairs[i - 1][0]);
  return v;
}

function rodMass(rod) {
  const pairs = stations(rod);
  const density = positive(obj(rod).density);
  return pairs && density ? density * volume(pairs) : null;
}

// ------------------------------------------------------------------------------------------
// The choices that shape the case: each reads its option from the case (null: the case does
// not say, keep the one on view) and rewrites the case when the user picks another.

const mode = (id) => ui.mode[id];
// A rod's fields, the tool's: an elastic striker has them too.
const rodKeys = () => schema.get("tool").keys;
// The fields of `group` (a medium, a force) of kind `kind`.
const kindKeys = (group, kind) => (schema.get(group).kinds || {})[kind] || [];
const rodStriker = () => mode("striker:model") === "rod";

const shapeMode = (rod) => ({
  id: `${rod}:shape`, label: "Cross-section", initial: "uniform",
  options: [["uniform", "uniform area"], ["profile", "profile S(x), a table"]],
  hint: "to a profile: the area at both ends; to uniform: the mean area (same mass)",
  read: (c) => {
    const r = obj(c[rod]);
    return r.profile !== undefined ? "profile" : r.area !== undefined ? "uniform" : null;
  },
  write: (c, to) => {
    const r = ensure(c, rod);
    if (to === "profile") {
      const area = r.area ?? null;
      delete r.area;
      place(r, "profile", { x: [0, r.length ?? null], area: [area, area] }, rod);
    } else {
      // The mean area keeps the rod's mass; the first area if the profile has no length yet.
      const pairs = stations(r);
      const first = Array.isArray(obj(r.profile).area) ? r.profile.area[0] : undefined;
      const area = pairs && pairs.at(-1)[0] > pairs[0][0]
        ? round(volume(pairs) / (pairs.at(-1)[0] - pairs[0][0])) : first;
      delete r.profile;
      if (area !== undefined && area !== null) place(r, "area", area, rod);
    }
  },
});

const MODES = {
  "striker:model": {
    id: "striker:model", label: "Model", initial: "lumped",
    options: [["lumped", "a lumped mass"], ["rod", "an elastic rod (a piston)"]],
    hint: "switching keeps the striker's mass",
    read: (c) => {
      const s = obj(c.striker);
      return s.mass !== undefined ? "lumped" : s.length !== undefined ? "rod" : null;
    },
    write: (c, to) => {
      const s = ensure(c, "striker");
      if (to === "rod") {
        stash.lumped = pick(s, ["mass"]);
        const tool = obj(c.tool);
        const density = positive(tool.density);
        const area = positive(tool.area) ?? (stations(tool) || [[0, null]])[0][1];
        const length = positive(s.mass) && density && area ? round(s.mass / (density * area)) : undefined;
        const rod = restore("rod", pick({ length, youngs_modulus: tool.youngs_modulus, density: tool.density, area },
                                        rodKeys()));
        delete s.mass;
        for (const [k, v] of Object.entries(rod)) place(s, k, v, "striker");
      } else {
        stash.rod = pick(s, rodKeys());
        const mass = rodMass(s);
        for (const k of rodKeys()) delete s[k];
        const lumped = restore("lumped", mass ? { mass: round(mass) } : {});
        for (const [k, v] of Object.entries(lumped)) place(s, k, v, "striker");
      }
    },
  },
  "striker:shape": shapeMode("striker"),
  "tool:shape": shapeMode("tool"),
  anvil: {
    id: "anvil", label: "Anvil between the striker and the tool", checkbox: true, initial: false,
    read: (c) => c.anvil !== undefined,
    write: (c, to) => {
      if (to) {
        place(c, "anvil", restore("anvil", { contact: pick(obj(c.contact), ["stiffness", "exponent"]) }), "");
      } else {
        stash.anvil = c.anvil;
        delete c.anvil;
      }
    },
  },
  "medium.kind": {
    id: "medium.kind", label: "Medium", initial: "none",
    options: () => [["none", "none: a free end"], ...schema.get("medium").choices],
    read: (c) => (c.medium === undefined ? "none" : obj(c.medium).kind ?? schema.get("medium.kind").default),
    write: (c, to, from) => {
      if (c.medium !== undefined) stash[`medium:${from}`] = c.medium;
      if (to === "none") {
        delete c.medium;
        return;
      }
      const old = obj(c.medium);
      place(c, "medium", stash[`medium:${to}`] ?? { kind: to, ...pick(old, kindKeys("medium", to)) }, "");
    },
  },
  "force.kind": {
    id: "force.kind", label: "Force on the striker", initial: "none",
    options: () => [["none", "none"], ...schema.get("force").choices],
    hint: "acts on a lumped striker only",
    read: (c) => (c.force === undefined ? "none" : obj(c.force).kind ?? null),
    write: (c, to, from) => {
      if (c.force !== undefined) stash[`force:${from}`] = c.force;
      if (to === "none") {
        delete c.force;
        return;
      }
      place(c, "force", stash[`force:${to}`] ?? { kind: to, ...pick(obj(c.force), kindKeys("force", to)) }, "");
    },
  },
  // A hammer at work: the drive and its cycles come and go together (the one needs the other),
  // and its cycles take the place of blows (they exclude each other).
  "drive.kind": {
    id: "drive.kind", label: "Drive", initial: "none",
    options: () => [["none", "none: one impact at the striker's velocity"], ...schema.get("drive.kind").choices],
    hint: "cycle after cycle: a return stroke, a work stroke and a blow",
    read: (c) => (c.drive === undefined ? "none" : obj(c.drive).kind ?? null),
    write: (c, to) => {
      if (to === "none") {
        Object.assign(stash, { drive: c.drive, cycles: c.cycles });
        delete c.drive;
        delete c.cycles;
        return;
      }
      if (c.blows !== undefined) stash.blows = c.blows;
      delete c.blows;
      place(c, "drive", restore("drive", { kind: to }), "");
      place(c, "cycles", restore("cycles", { count: 10 }), "");
    },
  },
  "drive:accumulator": {
    id: "drive:accumulator", label: "Gas accumulator on the supply", checkbox: true, initial: false,
    hint: "without it the supply holds its pressure",
    read: (c) => (c.drive === undefined ? null : obj(c.drive).accumulator !== undefined),
    write: (c, to) => {
      const drive = ensure(c, "drive");
      if (to) {
        place(drive, "accumulator", restore("accumulator", {}), "drive");
        if (stash.flow !== undefined) place(drive, "flow", stash.flow, "drive");
      } else {
        // a pump's flow needs the gas to buffer it
        Object.assign(stash, { accumulator: drive.accumulator, flow: drive.flow });
        delete drive.accumulator;
        delete drive.flow;
      }
    },
  },
  "drive.control.kind": {
    id: "drive.control.kind", label: "Stroke control", initial: "none",
    options: () => [["none", "none: the stroke as given"], ...schema.get("drive.control.kind").choices],
    hint: "adaptive: the next stroke moves toward the one that sets the tool by the target",
    read: (c) => (c.drive === undefined ? null : obj(obj(c.drive).control).kind ?? "none"),
    write: (c, to) => {
      const drive = ensure(c, "drive");
      if (to === "none") {
        stash.control = drive.control;
        delete drive.control;
        return;
      }
      place(drive, "control", restore("control", { kind: to }), "drive");
    },
  },
  "numerics:accuracy": {
    id: "numerics:accuracy", label: "Accuracy", initial: "tolerance",
    options: [["tolerance", "a tolerance: the solver picks the grid"], ["grid", "a fixed grid"]],
    read: (c) => (GRID_KEYS.slice(0, 3).some((k) => obj(c.numerics)[k] !== undefined) ? "grid" : "tolerance"),
    write: (c, to) => {
      const n = ensure(c, "numerics");
      const grid = { cells: schema.get("numerics.cells").implied };
      const [put, keep, kept] = to === "grid" ? [["tolerance"], "grid", grid] : [GRID_KEYS, "tolerance", {}];
      stash[to === "grid" ? "tolerance" : "grid"] = pick(n, put);
      for (const k of put) delete n[k];
      for (const [k, v] of Object.entries(restore(keep, kept))) place(n, k, v, "numerics");
    },
  },
};

// ------------------------------------------------------------------------------------------
// The sections of the form and what is in each, in order: a choice (`mode`), a field or a table
// (`path`, `table`), with when it is on view and a hint ({bounds} and {default} are the schema's).
// Everything else of a field (its kind, label, quantity, symbol, choices, default) is the
// schema's; a field of the schema that no section names is added at the end of its own.

const lumped = () => !rodStriker();
const grid = () => mode("numerics:accuracy") === "grid";
const anvil = () => mode("anvil") === true;

const driven = () => mode("drive.kind") !== "none";
const accumulator = () => driven() && mode("drive:accumulator") === true;
const adaptive = () => driven() && mode("drive.control.kind") !== "none";

const contactFields = (prefix, more = {}) => [
  { path: `${prefix}.stiffness`, hint: "G(δ) = c₁·δ^α while pressed", ...more },
  { path: `${prefix}.exponent`, hint: "0: a linear spring; 0.5: Hertz-like", ...more },
  { path: `${prefix}.tension_stiffness`, hint: "while the faces part (δ < 0); default {default}", ...more },
  { path: `${prefix}.damping`, ...more },
];

const GROUPS = [
  { id: "case", title: "Case", open: true, items: [
    { path: "name", hint: "names the job in the list" },
    { path: "description", multiline: true },
  ] },
  { id: "striker", title: "Striker", open: true, items: [
    { mode: "striker:model" },
    { path: "striker.velocity", hint: "+ toward the tool" },
    { path: "striker.mass", when: lumped },
    { path: "striker.length", when: rodStriker, couple: lastStation("striker") },
    { path: "striker.youngs_modulus", when: rodStriker },
    { path: "striker.density", when: rodStriker },
    { mode: "striker:shape", when: rodStriker },
    { path: "striker.area", when: () => rodStriker() && mode("striker:shape") === "uniform" },
    { table: "striker.profile", when: () => rodStriker() && mode("striker:shape") === "profile" },
  ] },
  { id: "tool", title: "Tool", open: true, items: [
    { path: "tool.length", couple: lastStation("tool") },
    { path: "tool.youngs_modulus" },
    { path: "tool.density" },
    { mode: "tool:shape" },
    { path: "tool.area", when: () => mode("tool:shape") === "uniform" },
    { table: "tool.profile", when: () => mode("tool:shape") === "profile" },
  ] },
  { id: "contact", title: "Contact", open: true, items: contactFields("contact") },
  { id: "anvil", title: "Anvil", open: false, items: [
    { mode: "anvil" },
    { path: "anvil.mass", when: anvil },
    { path: "anvil.velocity", when: anvil },
    // the paper has no symbols for the anvil's contact
    ...contactFields("anvil.contact", { when: anvil, prefix: "Anvil–tool", symbol: "" }),
  ] },
  // A medium's and a force's fields are on view as their kind has them (the schema's).
  { id: "medium", title: "Medium", open: true, items: [
    { mode: "medium.kind" },
    { path: "medium.stiffness", hint: () => (mode("medium.kind") === "bilinear" ? "while loading" : "") },
    { path: "medium.unloading_stiffness", hint: "≥ the loading stiffness" },
    { path: "medium.damping" },
    { path: "medium.ultimate_resistance" },
    { path: "medium.quake" },
    { path: "medium.damping_factor" },
  ] },
  { id: "force", title: "External force", open: false, items: [
    { mode: "force.kind" },
    { path: "force.amplitude" },
    { path: "force.omega" },
    { path: "force.start" },
    { path: "force.duration" },
  ] },
  { id: "blows", title: "Blows", open: false, items: [
    { path: "blows.count", when: () => !driven(), hint: "each lasts the duration T; empty: one blow" },
  ] },
  { id: "drive", title: "Work cycle", open: false, items: [
    { mode: "drive.kind" },
    { path: "cycles.count", when: driven, hint: "the first impact at the striker's velocity, the drive's after it" },
    { path: "drive.supply_pressure", when: driven },
    { path: "drive.return_pressure", when: driven },
    { path: "drive.front_area", when: driven, hint: "always at the supply: it returns the striker" },
    { path: "drive.rear_area", when: driven, hint: "switched by the valve; larger than the front" },
    { path: "drive.stroke", when: driven, hint: "back from the impact point, where the valve turns" },
    { path: "drive.valve_time", when: driven },
    { path: "drive.friction", when: driven },
    { mode: "drive:accumulator", when: driven },
    { path: "drive.accumulator.volume", when: accumulator },
    { path: "drive.accumulator.precharge", when: accumulator, hint: "below the supply pressure" },
    { path: "drive.accumulator.polytropic_exponent", when: accumulator, hint: "1: isothermal; 1.4: adiabatic" },
    { path: "drive.flow", when: accumulator, hint: "empty: the gas alone feeds the supply" },
    { mode: "drive.control.kind", when: driven },
    { path: "drive.control.target_set", when: adaptive },
    { path: "drive.control.min_stroke", when: adaptive },
    { path: "drive.control.max_stroke", when: adaptive },
  ] },
  { id: "gravity", title: "Gravity", open: false, items: [
    { path: "gravity.acceleration", hint: "9.81 for a vertical pile; empty: no weight" },
  ] },
  { id: "numerics", title: "Numerics", open: true, items: [
    { path: "numerics.duration" },
    { mode: "numerics:accuracy" },
    { path: "numerics.tolerance", when: () => !grid(), hint: "relative error asked of every headline quantity" },
    { path: "numerics.cells", when: grid, hint: "N = L/h" },
    { path: "numerics.time_step", when: grid, hint: "empty: chosen from the case" },
    { path: "numerics.scheme", when: grid, empty: "default (paper)" },
    { path: "numerics.gamma", hint: "{bounds}",
      when: () => grid() && [undefined, "paper"].includes(obj(current.numerics).scheme) },
    { path: "numerics.sigma", hint: "{bounds}", when: () => grid() && obj(current.numerics).scheme === "sigma" },
    { path: "numerics.end_masses", empty: "default (by scheme)" },
    { path: "numerics.model", empty: "default (rod)" },
  ] },
  { id: "outputs", title: "Outputs", open: false, items: [
    { table: "outputs.probes" },
    { path: "outputs.history_stride", hint: "keep every k-th step" },
    { path: "outputs.fields", hint: "displacement and stress at every cell" },
    { path: "outputs.field_stride", when: () => obj(current.outputs).fields === true, hint: "keep every k-th step" },
  ] },
];

// A problem on a field with no input of its own is shown at the input that makes it.
const ALIASES = {
  "striker.mass": ["striker:model"], "striker.length": ["striker:model"],
  "striker.youngs_modulus": ["striker:model"], "striker.density": ["striker:model"],
  "striker.area": ["striker:shape", "striker:model"], "striker.profile": ["striker:shape", "striker:model"],
  "tool.area": ["tool:shape"], "tool.profile": ["tool:shape"],
  medium: ["medium.kind"], force: ["force.kind"], "anvil.contact": ["anvil"], blows: ["blows.count"],
  gravity: ["gravity.acceleration"], drive: ["drive.kind"], cycles: ["cycles.count", "drive.kind"],
  "drive.accumulator": ["drive:accumulator"], "drive.control": ["drive.control.kind"],
};

// ------------------------------------------------------------------------------------------
// Building the form once; refresh() then shows the case in it.

const slug = (path) => `f-${path.replace(/[^\w]/g, "-")}`;
const text = (v) => (typeof v === "function" ? v() : v) || "";

function saveUnits() {
  try { localStorage.setItem(UNIT_STORAGE, JSON.stringify(ui.units)); } catch { /* private mode: not kept */ }
}

// The unit chosen for `key` (a field's path) among those of `quantity`.
function unitOf(key, quantity) {
  const offered = unitsOf(quantity);
  return offered.includes(ui.units[key]) ? ui.units[key] : offered[0];
}

// A unit select (several units) or the unit's text; `onchange(old, new)` re-expresses the value.
function unitControl(key, quantity, label, onchange) {
  const offered = unitsOf(quantity);
  if (offered.length < 2) return h("span", { class: "unit", id: `${slug(key)}-unit` }, offered[0]);
  const select = h("select", { class: "unit", "aria-label": `unit of ${label}` },
    offered.map((u) => h("option", { value: u, selected: u === unitOf(key, quantity) }, u)));
  let before = select.value;
  select.addEventListener("change", () => {
    ui.units[key] = select.value;
    saveUnits();
    onchange(before, select.value);
    before = select.value;
  });
  return select;
}

// The same quantity in another unit: the typed digits with the point moved.
function reexpress(input, from, to) {
  const moved = reexpressed(input.value, from, to);
  if (moved !== null) input.value = moved;
}

// A field as the form shows it: the schema's (schema.js), with its section's presentation (GROUPS).
function fieldOf(item) {
  const field = schema.get(item.path);
  const parent = item.path.split(".").slice(0, -1).join(".");
  const key = item.path.split(".").at(-1);
  const symbol = item.symbol ?? field.symbol ?? "";
  return {
    ...item,
    kind: item.multiline ? "textarea" : field.kind,
    label: item.prefix ? `${item.prefix}: ${field.title.toLowerCase()}` : field.title,
    quantity: field.quantity,
    // a symbol by its group's kind: a linear medium's stiffness is c₂, rock's k
    symbol: typeof symbol === "object" ? () => symbol[mode(`${parent}.kind`)] ?? "" : symbol,
    placeholder: field.default ?? field.implied,
    options: field.choices,
    bounds: field.bounds,
    when: item.when ?? (schema.get(parent).kinds ? () => kindKeys(parent, mode(`${parent}.kind`)).includes(key) : undefined),
  };
}

// "0.5 ≤ γ ≤ 1": the schema's bounds of field `f`, in its unit.
function boundsText(f) {
  const { minimum, maximum, exclusiveMinimum, exclusiveMaximum } = f.bounds;
  const unit = f.quantity ? unitOf(f.path, f.quantity) : "";
  const low = exclusiveMinimum ?? minimum;
  const high = exclusiveMaximum ?? maximum;
  return [low !== undefined && `${fromSI(low, unit)} ${exclusiveMinimum !== undefined ? "<" : "≤"}`, text(f.symbol) || f.label,
          high !== undefined && `${exclusiveMaximum !== undefined ? "<" : "≤"} ${fromSI(high, unit)}`, unit]
    .filter(Boolean).join(" ");
}

// A field's hint, its {bounds} and {default} the schema's, in the field's unit.
function hintOf(f) {
  const unit = f.quantity ? unitOf(f.path, f.quantity) : "";
  return text(f.hint).replace("{bounds}", () => boundsText(f)).replace("{default}", () => fromSI(f.placeholder, unit));
}

function symbolOf(item) {
  const symbol = text(item.symbol);
  return h("abbr", { class: "symbol", title: "the paper's symbol" }, symbol);
}

// `wanted` selected; a value the case holds that is not a choice is shown as such, to be changed.
function choose(select, wanted) {
  select.querySelectorAll("option.foreign").forEach((o) => { if (o.value !== wanted) o.remove(); });
  if (![...select.options].some((o) => o.value === wanted)) {
    select.append(h("option", { value: wanted, class: "foreign" }, `${wanted} (not a choice)`));
  }
  select.value = wanted;
}

// The input's value as it goes into the case.
function readField(f, input) {
  if (f.kind === "bool") return input.checked ? true : undefined;
  if (f.kind === "choice") return input.value === "" ? undefined : JSON.parse(input.value);
  if (f.kind === "text" || f.kind === "textarea") return input.value === "" ? undefined : input.value;
  return toSI(input.value, f.kind === "whole" ? "" : unitOf(f.path, f.quantity));
}

function showField(entry) {
  const { f, input } = entry;
  const value = getPath(current, f.path);
  if (f.kind === "bool") {
    input.checked = value === true;
    return;
  }
  if (f.kind === "choice") {
    choose(input, value === undefined ? "" : JSON.stringify(value));
    return;
  }
  // The text as typed stays while it says the same ("3.50" is not rewritten "3.5").
  if (same(readField(f, input), value)) return;
  input.value = f.kind === "text" || f.kind === "textarea" ? (typeof value === "string" ? value : fromSI(value))
    : fromSI(value, f.kind === "whole" ? "" : unitOf(f.path, f.quantity));
}

function fieldRow(item) {
  const f = fieldOf(item);
  const id = slug(f.path);
  const line = h("p", { class: "line", id: `${id}-line` });
  const aria = { id, "aria-describedby": `${id}-line`, spellcheck: "false", autocomplete: "off" };
  let input;
  let unit = null;
  if (f.kind === "textarea") input = h("textarea", { ...aria, rows: 2 });
  else if (f.kind === "bool") input = h("input", { ...aria, type: "checkbox" });
  else if (f.kind === "choice") {
    input = h("select", aria, h("option", { value: "" }, f.empty),
      f.options.map(([value, label]) => h("option", { value: JSON.stringify(value) }, label)));
  } else {
    input = h("input", { ...aria, type: "text", inputmode: f.kind === "whole" ? "numeric" : null,
                         placeholder: f.placeholder === undefined ? null : String(f.placeholder) });
  }
  const entry = { f, input, line, unit: null, wrap: null };
  if (f.quantity === "contact_stiffness" || f.kind === "whole") {
    unit = h("span", { class: "unit", id: `${id}-unit` }); // c₁'s follows α; a count has none
  } else if (f.quantity) {
    unit = unitControl(f.path, f.quantity, f.label.toLowerCase(), (from, to) => {
      reexpress(input, from, to);
      if (f.placeholder !== undefined) input.placeholder = fromSI(f.placeholder, to);
      if (!line.classList.contains("bad")) line.textContent = hintOf(f);
    });
    if (f.placeholder !== undefined) input.placeholder = fromSI(f.placeholder, unitOf(f.path, f.quantity));
  }
  if (unit && unit.tagName === "SPAN") input.setAttribute("aria-describedby", `${id}-unit ${id}-line`);
  entry.unit = unit;
  const symbol = symbolOf(f);
  entry.symbol = symbol;
  if (text(f.symbol)) input.title = `${f.label} ${text(f.symbol)}`;
  const label = h("label", { for: id, class: "name" }, f.label, " ", symbol);
  const wrap = h("div", { class: `field ${f.kind}`, "data-path": f.path },
    label, h("div", { class: "control" }, input, unit), line);
  wrap.itemWhen = f.when;
  entry.wrap = wrap;
  const event = ["bool", "choice"].includes(f.kind) ? "change" : "input";
  input.addEventListener(event, () => edit((c) => {
    const value = readField(f, input);
    setPath(c, f.path, value);
    if (f.couple) f.couple(c, value);
  }, input));
  fields.push(entry);
  targets.set(f.path, { wrap, inputs: [input], line, hint: () => hintOf(f) });
  return wrap;
}

function modeRow(item) {
  const m = MODES[item.mode];
  const id = slug(m.id);
  const line = h("p", { class: "line", id: `${id}-line` });
  const aria = { id, "aria-describedby": `${id}-line` };
  const input = m.checkbox ? h("input", { ...aria, type: "checkbox" })
    : h("select", aria, (typeof m.options === "function" ? m.options() : m.options)
      .map(([value, label]) => h("option", { value }, label)));
  ui.mode[m.id] = m.initial;
  input.addEventListener("change", () => {
    const from = ui.mode[m.id];
    const to = m.checkbox ? input.checked : input.value;
    if (to === from) return;
    ui.mode[m.id] = to;
    edit((c) => m.write(c, to, from), input);
  });
  const wrap = h("div", { class: `field mode${m.checkbox ? " bool" : ""}`, "data-mode": m.id },
    h("label", { for: id, class: "name" }, m.label), h("div", { class: "control" }, input), line);
  const entry = { m, item, input, wrap, line };
  modes.push(entry);
  targets.set(m.id, { wrap, inputs: [input], line, hint: () => m.hint || "" });
  return wrap;
}

// ------------------------------------------------------------------------------------------
// Station tables: a rod's profile (x and area, or diameter) and the probes (x).

function stationTable(path) {
  const rod = path.split(".")[0];
  const probes = path === "outputs.probes";
  const id = slug(path);
  const line = h("p", { class: "line", id: `${id}-line` });
  const column = (key, columnPath) => ({ key, path: columnPath, label: key, quantity: schema.get(columnPath).quantity });
  const columns = probes ? [column("x", path)] : [column("x", `${path}.x`), column("area", `${path}.area`)];
  const diameters = () => !probes && ui.diameters[rod] === true;
  const unitKey = (col) => (col.key === "area" && diameters() ? `${path}.diameter` : col.path);
  const quantityOf = (col) => (col.key === "area" && diameters() ? "length" : col.quantity);
  const tbody = h("tbody");
  const head = h("tr");
  const what = probes ? "probe" : "station";

  const arrays = () => columns.map((col) => {
    const v = getPath(current, col.path);
    return Array.isArray(v) ? v : [];
  });

  // A cell's value as it goes into the case: SI; a diameter as the area of its circle.
  function readCell(col, input) {
    const v = toSI(input.value, unitOf(unitKey(col), quantityOf(col)));
    if (col.key === "area" && diameters() && typeof v === "number") return (Math.PI * v * v) / 4;
    return v === undefined ? null : v;
  }

  function showCell(col, input, value) {
    if (same(readCell(col, input), value)) return;
    if (col.key === "area" && diameters() && finite(value) && value >= 0) {
      // Six digits: a diameter from an area is not exact, and 60 mm reads better than 59.99999.
      input.value = fromSI(round(Math.sqrt((4 * value) / Math.PI)), unitOf(unitKey(col), "length"));
    } else {
      input.value = fromSI(value, unitOf(unitKey(col), quantityOf(col)));
    }
  }

  // Write the columns' arrays with `mutate` applied. The profile's last station is the rod's
  // length: when `moved` says the last x changed, the length follows.
  function change(mutate, source = null, moved = false) {
    edit((c) => {
      const lists = columns.map((col) => {
        const v = getPath(c, col.path);
        return Array.isArray(v) ? v : [];
      });
      const n = Math.max(...lists.map((l) => l.length));
      lists.forEach((l) => { while (l.length < n) l.push(null); });
      mutate(lists);
      if (probes && !lists[0].length) {
        setPath(c, path, undefined);
        return;
      }
      columns.forEach((col, i) => setPath(c, col.path, lists[i]));
      const last = lists[0].at(-1);
      if (!probes && moved && positive(last)) setPath(c, `${rod}.length`, last);
    }, source);
  }

  function cellInput(col, row) {
    const label = col.key === "area" && diameters() ? "diameter" : col.label;
    const input = h("input", { type: "text", autocomplete: "off", spellcheck: "false", class: "cell",
                               "aria-label": `${label} of ${what} ${row}`, "aria-describedby": `${id}-line`,
                               "data-row": row, "data-col": col.key });
    input.addEventListener("input", () => change((lists) => {
      lists[columns.indexOf(col)][row] = readCell(col, input);
    }, input, col.key === "x" && row === tbody.rows.length - 1));
    return input;
  }

  function insertAfter(row) {
    change((lists) => lists.forEach((l) => {
      const [a, b] = [l[row], l[row + 1]];
      l.splice(row + 1, 0, finite(a) && finite(b) ? round((a + b) / 2, 12) : null);
    }));
    focusCell(row + 1, "x");
  }

  function remove(row) {
    change((lists) => lists.forEach((l) => l.splice(row, 1)), null, row === tbody.rows.length - 1);
    const rows = tbody.rows.length;
    if (rows) focusCell(Math.min(row, rows - 1), "x");
    else addButton?.focus();
  }

  function addProbe() {
    change((lists) => {
      const length = positive(obj(current.tool).length);
      lists[0].push(length ? round(length / 2, 12) : null);
    });
    focusCell(tbody.rows.length - 1, "x");
  }

  const focusCell = (row, key) => tbody.querySelector(`input[data-row="${row}"][data-col="${key}"]`)?.focus();

  function buildRows(n) {
    tbody.replaceChildren(...Array.from({ length: n }, (_, row) => h("tr", {},
      h("th", { scope: "row", class: "num" }, String(row)),
      columns.map((col) => h("td", {}, cellInput(col, row))),
      h("td", { class: "actions" }, h("span", {},
        probes ? null : h("button", { type: "button", class: "icon", title: "add a station after this one",
          "aria-label": `add a station after station ${row}`, disabled: row >= n - 1,
          onclick: () => insertAfter(row) }, "+"),
        h("button", { type: "button", class: "icon", title: `remove this ${what}`,
          "aria-label": `remove ${what} ${row}`, disabled: !probes && n <= 2,
          onclick: () => remove(row) }, "✕"))))));
  }

  function buildHead() {
    head.replaceChildren(h("th", { scope: "col" }, h("span", { class: "visually-hidden" }, what)),
      ...columns.map((col) => {
        const label = col.key === "area" && diameters() ? "Ø d" : col.label;
        const symbol = col.key === "area" && !diameters() ? " S" : "";
        return h("th", { scope: "col" }, label, symbol ? h("abbr", { class: "symbol", title: "the paper's symbol" }, symbol) : null, " ",
          unitControl(unitKey(col), quantityOf(col), `${label} (${what}s)`, (from, to) => {
            tbody.querySelectorAll(`input[data-col="${col.key}"]`).forEach((input) => reexpress(input, from, to));
          }));
      }),
      h("th", { scope: "col" }, h("span", { class: "visually-hidden" }, "add or remove")));
  }

  let addButton = null;
  const toggle = probes ? null : h("input", { type: "checkbox", id: `${id}-diameters` });
  if (toggle) {
    toggle.addEventListener("change", () => {
      ui.diameters[rod] = toggle.checked;
      buildHead();
      tbody.querySelectorAll('input[data-col="area"]').forEach((input) => {
        input.setAttribute("aria-label", `${toggle.checked ? "diameter" : "area"} of station ${input.dataset.row}`);
      });
      refreshTable(null);
    });
  }
  if (probes) addButton = h("button", { type: "button", class: "link add", onclick: addProbe }, "add a probe");

  const hint = probes
    ? "stations x along the tool, for stress histories"
    : `x from ${rod === "tool" ? "the struck end" : "the impact face"}; the last station is the length`;
  const caption = probes ? "Probes" : `Profile S(x) of the ${rod}`;
  const wrap = h("div", { class: `field table${probes ? " probes" : ""}`, "data-path": path },
    h("div", { class: "table-head" },
      h("span", { class: "name", id: `${id}-caption` }, caption),
      toggle && h("label", { class: "toggle" }, toggle, " diameters of a round section")),
    h("div", { class: "scroll" }, h("table", { class: "stations", "aria-labelledby": `${id}-caption` },
      h("thead", {}, head), tbody)),
    addButton, line);
  buildHead();

  function refreshTable(source) {
    const lists = arrays();
    const n = Math.max(...lists.map((l) => l.length));
    const focused = tbody.contains(document.activeElement) ? document.activeElement : null;
    if (tbody.rows.length !== n) {
      const where = focused && [focused.dataset.row, focused.dataset.col];
      buildRows(n);
      if (where) focusCell(where[0], where[1]);
    }
    tbody.querySelectorAll("input.cell").forEach((input) => {
      if (input === source) return;
      const col = columns.find((c) => c.key === input.dataset.col);
      showCell(col, input, lists[columns.indexOf(col)][Number(input.dataset.row)]);
    });
    // Both ends of a profile stay: the first station is the struck end, the last the length.
    tbody.querySelectorAll("button[aria-label^=remove]").forEach((b) => { b.disabled = !probes && n <= 2; });
    if (toggle) toggle.checked = diameters();
  }

  const table = {
    wrap, line, columns, refresh: refreshTable,
    cell: (row, key) => tbody.querySelector(`input[data-row="${row}"][data-col="${key}"]`),
    label: (key, row) => `${key === "area" && diameters() ? "diameter" : key} of ${what} ${row}`,
  };
  tables[path] = table;
  const target = { wrap, inputs: [], line, hint: () => hint };
  targets.set(path, target);
  columns.forEach((col) => targets.set(col.path, target));
  return wrap;
}

// ------------------------------------------------------------------------------------------

// The schema's fields that no section names, each added at the end of its own section (a field
// of the case itself in the first).
function unnamed(g) {
  const named = GROUPS.flatMap((group) => group.items.map((item) => item.path ?? item.mode));
  const tables = GROUPS.flatMap((group) => group.items.map((item) => item.table).filter(Boolean));
  const section = (path) => (GROUPS.some((group) => group.id === path.split(".")[0]) ? path.split(".")[0] : GROUPS[0].id);
  return [...schema.values()]
    .filter((f) => !["group", "table"].includes(f.kind) && !named.includes(f.path)
      && !tables.some((table) => f.path.startsWith(`${table}.`)) && section(f.path) === g.id)
    .map((f) => ({ path: f.path }));
}

function build() {
  try { Object.assign(ui.units, JSON.parse(localStorage.getItem(UNIT_STORAGE)) || {}); } catch { /* none kept */ }
  const status = h("p", { id: "form-status", class: "form-status", "aria-live": "polite" });
  $("case-fields").replaceChildren(status, ...GROUPS.map((g) => {
    const count = h("span", { class: "count", hidden: true });
    const digest = h("span", { class: "digest muted" });
    const details = h("details", { class: "group", "data-group": g.id, open: g.open },
      h("summary", {}, h("span", { class: "title" }, g.title), " ", digest, count),
      h("fieldset", {}, h("legend", { class: "visually-hidden" }, g.title),
        [...g.items, ...unnamed(g)].map((item) => {
          const el = item.mode ? modeRow(item) : item.table ? stationTable(item.table) : fieldRow(item);
          el.itemWhen ??= item.when;
          el.itemPath = item.path || item.table;
          return el;
        })));
    groups.push({ g, details, count, digest });
    return details;
  }));
  placeProblems([]); // the hints in the lines problems will take
}

// Whether an element of the form is on view: its condition holds, or the case gives its field
// (a field the choice does not expect stays reachable, to be corrected or emptied).
function visible(el) {
  if (!el.itemWhen || el.itemWhen()) return true;
  const path = el.itemPath;
  return path !== undefined && getPath(current, path) !== undefined;
}

function contactUnit(prefix) {
  const alpha = getPath(current, `${prefix}.exponent`);
  if (!finite(alpha)) return ["N/m", h("sup", {}, "1+α")];
  return alpha === 0 ? ["N/m"] : ["N/m", h("sup", {}, fromSI(round(1 + alpha, 12)))];
}

const DIGESTS = {
  contact: () => (current.anvil !== undefined ? "striker–anvil" : "striker–tool"),
  anvil: () => (isObject(current.anvil) ? (positive(current.anvil.mass) ? `${short(current.anvil.mass)} kg` : "mass ?") : "none"),
  force: () => (current.force === undefined ? "none" : String(obj(current.force).kind ?? "")),
  blows: () => (obj(current.blows).count !== undefined ? String(current.blows.count) : "one"),
  drive: () => (current.drive === undefined ? "none" : `${obj(current.cycles).count ?? "?"} cycles`),
  outputs: () => {
    const probes = obj(current.outputs).probes;
    const n = Array.isArray(probes) ? probes.length : 0;
    return `${n} probe${n === 1 ? "" : "s"}${obj(current.outputs).fields === true ? ", fields" : ""}`;
  },
};

// Show the case in the form; `source`, the input being typed in, keeps its text.
function refresh(source = null) {
  for (const { m, input } of modes) {
    const read = m.read(current);
    if (read !== null) ui.mode[m.id] = read;
    if (m.checkbox) input.checked = ui.mode[m.id] === true;
    else if (input !== source) {
      choose(input, String(ui.mode[m.id]));
    }
  }
  for (const { wrap } of [...modes, ...fields]) wrap.hidden = !visible(wrap);
  for (const table of Object.values(tables)) {
    table.wrap.hidden = !visible(table.wrap);
    if (!table.wrap.hidden) table.refresh(source);
  }
  for (const entry of fields) {
    if (entry.input !== source) showField(entry);
    const { f, unit, symbol } = entry;
    if (f.quantity === "contact_stiffness") unit.replaceChildren(...contactUnit(f.path.replace(/\.stiffness$/, "")));
    if (typeof f.symbol === "function") symbol.textContent = f.symbol();
    if (typeof f.hint === "function" && !entry.line.classList.contains("bad")) entry.line.textContent = hintOf(f);
  }
  for (const { g, digest } of groups) digest.textContent = DIGESTS[g.id] ? DIGESTS[g.id]() : "";
  $("case-fields").classList.toggle("stale", stale);
  draw();
}

// ------------------------------------------------------------------------------------------
// The form and the JSON: each follows the other.

function edit(change, source) {
  if (!isObject(current)) current = {};
  change(current);
  $("case-json").value = JSON.stringify(current, null, 2); // no event: the form is already up to date
  stale = false;
  refresh(source);
  scheduleCheck();
}

function fromText() {
  const area = $("case-json");
  stash = {}; // a new case: what was put aside belonged to the old one
  if (!area.value.trim()) {
    current = {};
    stale = false;
    cancelCheck();
    placeProblems([]);
    setStatus("", "");
    refresh();
    return;
  }
  let parsed;
  try { parsed = JSON.parse(area.value); } catch { parsed = undefined; }
  if (!isObject(parsed)) {
    // Left as it was: editor.js names the syntax error on Run.
    stale = true;
    cancelCheck();
    $("case-fields").classList.add("stale");
    setStatus("stale", "JSON syntax error: the form shows the last case that parsed.");
    return;
  }
  current = parsed;
  stale = false;
  refresh();
  scheduleCheck();
}

// ------------------------------------------------------------------------------------------
// The service's check, as the user types: the problems a Run would be refused with.

let checkTimer = null;
let checkSeq = 0;
let checkAbort = null;

function setStatus(kind, message) {
  const status = $("form-status");
  if (!status) return;
  status.className = `form-status ${kind}`;
  status.textContent = message;
}

function cancelCheck() {
  clearTimeout(checkTimer);
  if (checkAbort) checkAbort.abort();
  checkSeq += 1;
}

function scheduleCheck() {
  cancelCheck();
  const seq = checkSeq;
  checkTimer = setTimeout(() => check(seq), CHECK_DELAY_MS);
}

async function check(seq) {
  const controller = new AbortController();
  checkAbort = controller;
  setStatus("checking", "Checking the case with the service…");
  let problems;
  try {
    ({ problems } = await getJSON("/v1/cases/check", {
      method: "POST", headers: { "Content-Type": "application/json" }, body: $("case-json").value,
      signal: controller.signal, askKey: false }));
  } catch (error) {
    // Text that is not JSON is refused as POST /v1/jobs refuses it, with its problems.
    if (error instanceof ApiError && error.status === 422 && Array.isArray(error.detail)) problems = error.detail;
    else if (seq === checkSeq) setStatus("", ""); // no check to be had (no key, the service away): Run still says
  }
  if (seq !== checkSeq || !problems) return; // a later edit supersedes this answer
  const rest = placeProblems(problems);
  const n = problems.length;
  const box = $("case-errors");
  if (rest.length) {
    showProblems(box, `${rest.length === n ? "The service finds" : "Also"} ${rest.length} problem${rest.length === 1 ? "" : "s"} in fields the form does not show:`, rest);
  } else {
    showProblems(box, null);
  }
  setStatus(n ? "bad" : "ok", n ? `The service finds ${n} problem${n === 1 ? "" : "s"} in this case.`
                                : "The service finds no problem in this case.");
}

// Where a problem's field is shown: its input, a table's cell, or the input that makes it.
function locate(field) {
  const cell = /^((?:striker|tool)\.profile)\.(x|area)\[(\d+)\]$/.exec(field)
    || /^(outputs\.probes)\[(\d+)\]$/.exec(field);
  if (cell) {
    const [, path, key, row] = cell.length === 4 ? cell : [cell[0], cell[1], "x", cell[2]];
    const table = tables[path];
    if (table && !table.wrap.hidden) {
      const input = table.cell(row, key);
      return { target: targets.get(path), input, prefix: input ? table.label(key, row) : field };
    }
  }
  for (const path of [field, ...(ALIASES[field] || [])]) {
    const target = targets.get(path);
    if (target && !target.wrap.hidden) {
      return { target, input: null, prefix: path === field ? null : field };
    }
  }
  return null;
}

function placeProblems(problems) {
  for (const target of new Set(targets.values())) {
    target.line.classList.remove("bad");
    target.line.textContent = target.hint();
  }
  $("case-fields").querySelectorAll("[aria-invalid]").forEach((el) => el.removeAttribute("aria-invalid"));
  const placed = new Map();
  const rest = [];
  for (const problem of problems) {
    const where = problem && typeof problem.field === "string" ? locate(problem.field) : null;
    if (!where) {
      rest.push(problem);
      continue;
    }
    if (!placed.has(where.target)) placed.set(where.target, []);
    placed.get(where.target).push(where.prefix ? `${where.prefix}: ${problem.message}` : problem.message);
    for (const input of where.input ? [where.input] : where.target.inputs) input.setAttribute("aria-invalid", "true");
  }
  for (const [target, messages] of placed) {
    target.line.classList.add("bad");
    target.line.textContent = messages.join("; ");
  }
  for (const { details, count } of groups) {
    const n = [...placed.keys()].filter((t) => details.contains(t.wrap))
      .reduce((sum, t) => sum + placed.get(t).length, 0);
    count.hidden = !n;
    count.textContent = `${n} problem${n === 1 ? "" : "s"}`;
  }
  return rest;
}

// ------------------------------------------------------------------------------------------
// The drawing: the striker, the anvil, the tool and the medium, to scale along and across the
// axis (or with the radii enlarged by a stated factor when the tool is slender).

const SVG_NS = "http://www.w3.org/2000/svg";

function svg(tag, attrs = {}, ...children) {
  const el = document.createElementNS(SVG_NS, tag);
  for (const [name, value] of Object.entries(attrs)) {
    if (value !== null && value !== undefined && value !== false) el.setAttribute(name, value);
  }
  el.append(...children.flat().filter((c) => c !== null && c !== undefined && c !== false));
  return el;
}

const short = (v) => String(round(v, 4));
const meters = (v) => (v < 1 ? `${short(inUnit(v, "mm"))} mm` : `${short(v)} m`);

// A rod's outline as an SVG path: x from `origin` (px) in direction `dir`, radii ×`k`.
function rodPath(pairs, s, k, origin, dir, cy) {
  const top = [];
  for (let i = 1; i < pairs.length; i++) {
    const [[x0, a0], [x1, a1]] = [pairs[i - 1], pairs[i]];
    // The area is linear between stations, so the radius is not: sample it.
    for (let j = i === 1 ? 0 : 1; j <= 8; j++) {
      const t = j / 8;
      const r = Math.sqrt((a0 + (a1 - a0) * t) / Math.PI);
      top.push([origin + dir * (x0 + (x1 - x0) * t) * s, r * s * k]);
    }
  }
  const points = [...top.map(([x, r]) => [x, cy - r]), ...top.reverse().map(([x, r]) => [x, cy + r])];
  return `M${points.map(([x, y]) => `${x.toFixed(1)},${y.toFixed(1)}`).join("L")}Z`;
}

function picture(c, width) {
  const H = DRAWING_HEIGHT;
  const cy = 72;
  const hmax = 36; // the largest radius drawn, px
  const margin = 8;
  const tool = obj(c.tool);
  const striker = obj(c.striker);
  const rod = rodStriker();
  const hasAnvil = isObject(c.anvil);
  const med = isObject(c.medium) ? c.medium : null;
  const toolPairs = stations(tool);
  const toolLength = positive(tool.length) ?? (toolPairs ? toolPairs.at(-1)[0] : null);
  const strikerPairs = rod ? stations(striker) : null;
  const strikerLength = rod ? positive(striker.length) ?? (strikerPairs ? strikerPairs.at(-1)[0] : null) : null;

  const BLOCK = 46;
  const GAP = 8;
  const ANVIL = 14;
  const MEDIUM = 34;
  const STAND_IN = { tool: 90, striker: 36 }; // px for a length the case does not give
  const fixed = 2 * margin + (rod ? 0 : BLOCK) + GAP + (hasAnvil ? ANVIL + 4 : 0) + (med ? MEDIUM : 0)
    + (toolLength ? 0 : STAND_IN.tool) + (rod && !strikerLength ? STAND_IN.striker : 0);
  const total = (toolLength ?? 0) + (strikerLength ?? 0); // m drawn to scale
  let s = total > 0 ? Math.max(width - fixed, 40) / total : 0; // px per m
  const radii = [...(toolPairs || []), ...(strikerPairs || [])].map(([, a]) => Math.sqrt(a / Math.PI));
  const rmax = radii.length ? Math.max(...radii) : 0;
  if (rmax && s && rmax * s > hmax) s = hmax / rmax; // a stubby rod: the height limits the scale
  let k = 1;
  if (rmax && s && rmax * s < 8) k = [2, 5, 10, 20, 50, 100, 200, 500, 1000, 1e4].find((f) => rmax * s * f >= 10) ?? 1e4;
  const standInR = 10;

  const parts = [];
  const labels = [];
  let x = margin;

  // The striker
  const velocity = striker.velocity;
  const wText = finite(velocity) ? `W₁ = ${short(velocity)} m/s` : "W₁ ?";
  const arrow = finite(velocity) && velocity < 0 ? `← ${wText}` : `${wText} →`;
  if (!rod) {
    const mass = positive(striker.mass);
    parts.push(svg("rect", { x, y: cy - 22, width: BLOCK, height: 44, rx: 3, class: mass ? "body striker" : "body striker guess" }));
    parts.push(svg("text", { x: x + BLOCK / 2, y: cy - 4, class: "inside", "text-anchor": "middle" }, "m₁"),
      svg("text", { x: x + BLOCK / 2, y: cy + 11, class: "inside", "text-anchor": "middle" },
        mass ? `${short(mass)} kg` : "?"));
    labels.push(svg("text", { x, y: 14, class: "label" }, arrow));
    if (isObject(c.force)) labels.push(svg("text", { x, y: cy + 36, class: "label" }, "+ R(t)"));
    x += BLOCK + GAP;
  } else {
    const px = strikerLength ? strikerLength * s : STAND_IN.striker;
    const face = x + px;
    if (strikerPairs && strikerLength) {
      parts.push(svg("path", { d: rodPath(strikerPairs, s, k, face, -1, cy), class: "body striker" }));
    } else {
      parts.push(svg("rect", { x, y: cy - standInR, width: px, height: 2 * standInR, class: "body striker guess" }));
    }
    labels.push(svg("text", { x, y: 14, class: "label" }, arrow));
    labels.push(svg("text", { x, y: H - 26, class: "label" }, strikerLength ? `striker ${meters(strikerLength)}` : "striker: length ?"));
    x = face + GAP;
  }

  // The anvil, as tall as the tool's struck end and a little more
  if (hasAnvil) {
    const r0 = toolPairs ? Math.sqrt(toolPairs[0][1] / Math.PI) * s * k : standInR;
    const half = Math.min(Math.max(r0 * 1.3, 10), hmax);
    parts.push(svg("rect", { x, y: cy - half, width: ANVIL, height: 2 * half, rx: 2, class: "body anvil" }));
    labels.push(svg("text", { x: x + ANVIL / 2, y: 30, class: "label", "text-anchor": "middle" }, "anvil"));
    x += ANVIL + 4;
  }

  // The tool
  const toolPx = toolLength ? toolLength * s : STAND_IN.tool;
  const toolStart = x;
  if (toolPairs && toolLength) {
    parts.push(svg("path", { d: rodPath(toolPairs, s, k, x, 1, cy), class: "body tool" }));
  } else {
    parts.push(svg("rect", { x, y: cy - standInR, width: toolPx, height: 2 * standInR, class: "body tool guess" }));
  }
  const probes = obj(c.outputs).probes;
  if (Array.isArray(probes) && toolLength) {
    for (const p of probes) {
      if (finite(p) && p >= 0 && p <= toolLength) {
        parts.push(svg("line", { x1: x + p * s, x2: x + p * s, y1: cy - 5, y2: cy + 5, class: "probe" }));
      }
    }
  }
  labels.push(svg("text", { x: x + toolPx / 2, y: H - 26, class: "label", "text-anchor": "middle" },
    toolLength ? `tool L = ${meters(toolLength)}` : "tool: length ?"));
  x += toolPx;

  // The medium at the working end
  if (med) {
    const names = { linear: "medium (linear)", bilinear: "rock (bilinear)", smith: "soil (Smith)" };
    const kind = med.kind ?? "linear";
    parts.push(svg("rect", { x, y: cy - hmax, width: MEDIUM, height: 2 * hmax, class: "medium", fill: "url(#drawing-hatch)" }));
    labels.push(svg("text", { x: x + MEDIUM, y: 14, class: "label", "text-anchor": "end" }, names[kind] || String(kind)));
    x += MEDIUM;
  }
  const axis = svg("line", { x1: margin - 2, x2: Math.min(x + 2, width), y1: cy, y2: cy, class: "axis" });

  // The scale bar: a round length 30–110 px long
  const scale = [];
  if (s > 0) {
    const bar = [1e-3, 2e-3, 5e-3, 1e-2, 2e-2, 5e-2, 0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000]
      .filter((v) => v * s <= 110).at(-1) ?? 1e-3;
    const y = H - 9;
    const px = bar * s;
    scale.push(svg("path", { d: `M${margin},${y - 4}V${y}H${margin + px}V${y - 4}`, class: "scale" }),
      svg("text", { x: margin + px + 6, y: y + 1, class: "label" },
        `${meters(bar)}${k > 1 ? `; radii ×${k}` : ""}`));
  }

  const hatch = svg("pattern", { id: "drawing-hatch", width: 6, height: 6, patternUnits: "userSpaceOnUse",
                                 patternTransform: "rotate(45)" },
    svg("rect", { width: 6, height: 6, class: "hatch-ground" }), svg("line", { x1: 0, y1: 0, x2: 0, y2: 6, class: "hatch" }));
  return {
    node: svg("svg", { viewBox: `0 0 ${width} ${H}`, width, height: H, class: "case-drawing", "aria-hidden": "true",
                       "data-scale": s ? String(s) : null, "data-radii": String(k) },
      svg("defs", {}, hatch), axis, parts, labels, scale),
    k, s, toolStart,
  };
}

// The caption says in words what the drawing shows: lengths and masses.
function captionText(c) {
  const tool = obj(c.tool);
  const striker = obj(c.striker);
  const bits = [];
  const toolMass = rodMass(tool);
  bits.push(`Tool ${positive(tool.length) ? meters(tool.length) : "?"}${toolMass ? `, ${short(toolMass)} kg` : ""}`);
  const strikerMass = rodStriker() ? rodMass(striker) : positive(striker.mass);
  bits.push(`${rodStriker() ? "striker rod" : "striker"} ${strikerMass ? `${short(strikerMass)} kg` : "?"}`);
  if (isObject(c.anvil)) bits.push(`anvil ${positive(c.anvil.mass) ? `${short(c.anvil.mass)} kg` : "?"}`);
  return `${bits.join(" · ")}.`;
}

let lastWidth = 0;
function draw() {
  const figure = $("drawing");
  const width = Math.max(Math.floor(figure.clientWidth), 240);
  lastWidth = width;
  let node;
  let caption;
  try {
    const drawn = picture(current, width);
    node = drawn.node;
    const scale = !drawn.s ? "Not to scale: no length yet."
      : drawn.k > 1 ? `Drawn to scale along the axis, the radii ×${drawn.k}.` : "Drawn to scale.";
    caption = `${captionText(current)} ${scale}`;
  } catch (error) {
    // Whatever the case holds, the form stays usable.
    node = svg("svg", { viewBox: `0 0 ${width} ${DRAWING_HEIGHT}`, width, height: DRAWING_HEIGHT, class: "case-drawing" });
    caption = `Not drawn: ${error.message}`;
  }
  figure.replaceChildren(node, h("figcaption", { class: "small muted" }, caption));
}

// ------------------------------------------------------------------------------------------

// The form, once the case's schema has come; until then, and if it cannot be had, the case JSON
// is edited alone.
export async function buildForm() {
  try {
    schema = await caseFields();
  } catch (error) {
    $("case-fields").replaceChildren(h("p", { id: "form-status", class: "form-status bad" },
      `No form: the case's schema could not be loaded (${describe(error)}). The case JSON below still runs.`));
    return;
  }
  build();
  const area = $("case-json");
  area.addEventListener("input", fromText);
  // Run answers for the case as it is: a check still pending would only repeat it, and its
  // answer must not replace the refusal editor.js shows.
  $("case-form").addEventListener("submit", () => {
    cancelCheck();
    setStatus("", "");
  });
  if (area.value.trim()) fromText();
  else refresh();
  if (window.ResizeObserver) {
    new ResizeObserver(() => {
      if (Math.floor($("drawing").clientWidth) !== lastWidth) draw();
    }).observe($("drawing"));
  }
}
