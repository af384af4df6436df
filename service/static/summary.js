// A run's pulse summary as cards, in the views' units: the job view's, an optimum's; PULSE, its
// headline quantities, also heads the comparison's table.
import { card, fmt, h, table } from "./dom.js";
import { inUnit, shown, shownUnit } from "./units.js";

const inShown = (value, quantity) => fmt(shown(value, quantity));
const headed = (label, quantity) => `${label} (${shownUnit(quantity)})`;

// A quantity's estimated relative error, or why it has none (on hover).
function errorCell(s, key) {
  const estimate = (s.error_estimate || {})[key];
  if (estimate !== undefined) {
    const over = estimate > (s.tolerance ?? 0.01);
    return h("td", { class: over ? "num error over" : "num error" }, `±${fmt(100 * estimate, 2)}%`);
  }
  const reason = (s.not_estimated || {})[key];
  return h("td", { class: "num error muted", title: reason || "" }, reason ? "n/a" : "");
}

// A row of the pulse table; `key` names the summary's quantity, for whoever reads the page by machine.
function pulseRow(s, label, key, value, unit, x = "", t = "") {
  return h("tr", { "data-quantity": key },
    h("th", {}, label), h("td", { class: "num value" }, value), h("td", { class: "unit" }, unit),
    errorCell(s, key), h("td", { class: "num" }, x), h("td", { class: "num" }, t));
}

// An extreme's place and time, blank without one.
const placed = (extreme) => (extreme ? [inShown(extreme.x, "length"), inShown(extreme.time, "time")] : ["", ""]);

// The pulse's headline quantities, as the pulse table and a comparison show them: `key` is the
// summary's name (its error estimate's too), `read` its SI value, `quantity` what it measures,
// `where` its place and time in the pulse table; an `optional` one is listed only when the case
// has it (a penetration needs a medium).
export const PULSE = [
  { label: "Co-impact time", key: "co_impact_time", quantity: "time", read: (s) => s.co_impact_time },
  { label: "Peak contact force", key: "peak_contact_force", quantity: "force", read: (s) => s.peak_contact_force?.value,
    where: (s) => ["", inShown(s.peak_contact_force.time, "time")] },
  { label: "Max compressive stress", key: "max_compressive_stress", quantity: "stress",
    read: (s) => s.max_compressive_stress?.value, where: (s) => placed(s.max_compressive_stress) },
  { label: "Max tensile stress", key: "max_tensile_stress", quantity: "stress", read: (s) => s.max_tensile_stress?.value,
    where: (s) => placed(s.max_tensile_stress) },
  { label: "Striker rebound velocity", key: "striker_rebound_velocity", quantity: "speed",
    read: (s) => s.striker_rebound_velocity,
    where: (s) => ["", s.contacts?.length ? inShown(s.contacts[0].end, "time") : ""] },
  { label: "Energy to the medium", key: "energy.to_medium", quantity: "energy", read: (s) => s.energy?.to_medium },
  { label: "Transfer efficiency", key: "energy.transfer_efficiency", quantity: "ratio",
    read: (s) => s.energy?.transfer_efficiency },
  { label: "Deepest penetration", key: "medium_penetration.max", quantity: "length", read: (s) => s.medium_penetration?.max,
    optional: true },
  { label: "Permanent penetration", key: "medium_penetration.permanent", quantity: "length",
    read: (s) => s.medium_penetration?.permanent, optional: true },
];

// A pulse quantity's value in its unit, or null when the summary has none.
export function pulseValue({ read, quantity }, s) {
  const value = read(s);
  return typeof value === "number" ? shown(value, quantity) : null;
}

export function pulseCard(s) {
  const contacts = s.contacts || [];
  const us = (t) => inShown(t, "time");
  return card("Pulse",
    table("pulse", ["", "value", "unit", "error (est.)", headed("at x", "length"), headed("at t", "time")], [
      PULSE.filter((q) => !q.optional || pulseValue(q, s) !== null).map((q) =>
        pulseRow(s, q.label, q.key, fmt(pulseValue(q, s)), shownUnit(q.quantity), ...(q.where ? q.where(s) : []))),
      pulseRow(s, "Contacts", "contacts_total", String(s.contacts_total ?? contacts.length), ""),
    ]),
    contacts.length > 1 && h("details", {},
      h("summary", {}, `All ${contacts.length} contact intervals`),
      table("contacts", ["#", headed("start", "time"), headed("end", "time"), headed("duration", "time")],
        contacts.map((c, i) => h("tr", {}, h("td", { class: "num" }, String(i + 1)), h("td", { class: "num" }, us(c.start)),
          h("td", { class: "num" }, us(c.end)), h("td", { class: "num" }, us(c.end - c.start)))))));
}

// The terms the input ends as; those marked `rare` belong to some models only (an elastic
// striker, an anvil, a medium that yields, blows) and are listed when they are not 0.
const ENERGY_TERMS = [
  ["striker_kinetic", "Striker, kinetic"],
  ["striker_strain", "Striker, strain", "rare"],
  ["anvil_kinetic", "Anvil, kinetic", "rare"],
  ["tool_kinetic", "Tool, kinetic"],
  ["tool_strain", "Tool, strain"],
  ["contact_potential", "Contact, potential"],
  ["medium_potential", "Medium, potential"],
  ["medium_plastic", "Medium, plastic", "rare"],
  ["dissipated_contact", "Dissipated in the contact"],
  ["dissipated_medium", "Dissipated in the medium"],
  ["striker_withdrawn", "Withdrawn with the striker", "rare"],
  ["dissipated_between_blows", "Spent as the tool came to rest between blows", "rare"],
  ["numerical", "Lost by the scheme"],
];

function energyCard(e) {
  const input = e.initial + e.external_work;
  const share = (value) => (input ? ((100 * value) / input).toFixed(1) : "—");
  const row = (label, key, value, className = null) => h("tr", { "data-energy": key, class: className },
    h("th", {}, label), h("td", { class: "num value" }, inShown(value, "energy")), h("td", { class: "num" }, share(value)));
  const residual = input - ENERGY_TERMS.reduce((sum, [key]) => sum + (e[key] ?? 0), 0);
  const tiny = Math.abs(residual) < 1e-9 * Math.max(Math.abs(input), 1);
  return card("Energy audit",
    table("energy", ["", shownUnit("energy"), "% of input"], [
      row("Striker at impact", "initial", e.initial),
      row("External force's work", "external_work", e.external_work),
      row("Input", "input", input, "total"),
      row("To the medium", "to_medium", e.to_medium, "highlight"),
      h("tr", { class: "group" }, h("th", { colspan: 3 }, "At the end of the run")),
      ENERGY_TERMS.filter(([key, , rare]) => !rare || e[key]).map(([key, label]) => row(label, key, e[key])),
      h("tr", { class: "total" }, h("th", {}, "Balance (input − terms)"),
        h("td", { class: "num" }, tiny ? "0" : inShown(residual, "energy")),
        h("td", { class: "num" }, tiny ? "0" : share(residual))),
      h("tr", {}, h("th", {}, "Largest energy created"), h("td", {}),
        h("td", { class: "num" }, fmt(100 * e.max_excess_fraction, 3))),
    ]));
}

// The summary's blows table, a row a blow: [key, label, quantity].
const BLOW_COLUMNS = [
  ["peak_contact_force", "peak contact force", "force"],
  ["max_compressive_stress", "max compressive stress", "stress"],
  ["to_medium", "to the medium", "energy"],
  ["transfer_efficiency", "transfer efficiency", "ratio"],
  ["permanent_penetration", "permanent penetration", "length"],
  ["set", "set", "length"],
];

function blowsCard(blows) {
  return card(`Blows (${blows.length})`,
    table("blows", ["blow", ...BLOW_COLUMNS.map(([, label, quantity]) => headed(label, quantity))],
      blows.map((b, i) => h("tr", { "data-blow": i + 1 }, h("th", {}, String(i + 1)),
        BLOW_COLUMNS.map(([key, , quantity]) => h("td", { class: "num" }, inShown(b[key], quantity)))))));
}

// A hammer at work's cycle (`cycle`): [key, label, quantity, unit it is shown in (else the
// quantity's)], its error estimate's key being `cycle.<key>`.
const CYCLE_ROWS = [
  ["impact_energy", "Impact energy", "energy"],
  ["frequency", "Blows per second", "frequency", "Hz"],
  ["impact_power", "Impact power", "power"],
  ["hydraulic_power", "Hydraulic power", "power"],
  ["efficiency", "Efficiency, hydraulic to the medium", "ratio"],
  ["penetration_rate", "Penetration rate", "speed"],
];

function cycleCard(s) {
  const c = s.cycle;
  const last = c.impact_velocity.length - 1;
  const value = (v, quantity, unit) => fmt(unit ? inUnit(v, unit) : shown(v, quantity));
  return card(`Work cycle (${c.impact_velocity.length} blows)`,
    table("cycle", ["", "value", "unit", "error (est.)"], [
      pulseRow(s, "Last impact velocity", "cycle.impact_velocity", fmt(c.impact_velocity[last]), "m/s"),
      CYCLE_ROWS.map(([key, label, quantity, unit]) =>
        pulseRow(s, label, `cycle.${key}`, value(c[key], quantity, unit), unit ?? shownUnit(quantity))),
      pulseRow(s, "Last stroke", "cycle.stroke", inShown(c.stroke[last], "length"), shownUnit("length")),
    ]),
    h("p", { class: "muted small" }, c.periodic
      ? "The last cycles repeat: the figures are those of a hammer at work."
      : "The cycles had not settled into a repeating one: the figures are the last cycles', still changing."));
}

function modelCard(s) {
  const n = s.numerics || {};
  const pair = (label, value) => h("tr", {}, h("th", {}, label), h("td", { class: "num" }, value));
  const rows = [
    pair("Model", s.model), pair("Scheme", s.scheme), pair("Cells", n.cells ?? "—"),
    pair(headed("Time step", "time"), inShown(n.time_step, "time")), pair("Steps", n.steps ?? "—"),
    n.scheme === "paper" && pair("γ", fmt(n.gamma, 3)), n.scheme === "sigma" && pair("σ", fmt(n.sigma, 3)),
    pair("Courant number", fmt(n.courant, 3)),
  ];
  if (s.tolerance !== null && s.tolerance !== undefined) rows.push(pair("Tolerance", String(s.tolerance)));
  if (s.error_estimate) {
    rows.push(pair("Estimated error (worst)", `${fmt(100 * s.error_estimate.worst, 2)}%`),
      pair("Grids run", (s.runs || []).map((r) => r.cells).join(", ")));
  }
  return card("Model and numerics", h("table", { class: "model" }, h("tbody", {}, rows)),
    h("p", { class: "why" }, h("strong", {}, "Why: "), s.why || "—"));
}

export function warningsBanner(warnings) {
  return warnings.length
    ? h("div", { class: "banner warning" }, h("p", { class: "title" },
        `${warnings.length} warning${warnings.length === 1 ? "" : "s"}`), h("ul", {}, warnings.map((w) => h("li", {}, w))))
    : h("p", { class: "muted small" }, "No warnings.");
}

// The summary's cards, in the order the job view shows them.
export function summaryCards(s) {
  return [
    warningsBanner(s.warnings || []),
    pulseCard(s),
    s.cycle ? cycleCard(s) : null,
    s.blows && s.blows.length ? blowsCard(s.blows) : null, // null: a case without blows
    h("div", { class: "pair" }, energyCard(s.energy), modelCard(s)),
  ].filter(Boolean);
}
