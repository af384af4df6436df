// The one table of the page's quantities and their units, for every view: the form, the summary,
// the charts, the comparison, the sweep and the studies. The case's schema names each field's
// quantity (solver/case.py); a series' axis names its SI unit.

// Each quantity's units, the SI one first: every one a power of ten of it, so that converting a
// typed value moves its decimal point and never multiplies (3.5 mm is read as the text "0.0035",
// the double nearest it). `shown`: the unit the views show it in (the SI one if none).
export const QUANTITIES = {
  length: { units: [["m", 0], ["mm", -3], ["cm", -2]], shown: "mm" },
  mass: { units: [["kg", 0], ["g", -3], ["t", 3]] },
  speed: { units: [["m/s", 0]] },
  acceleration: { units: [["m/s²", 0]] },
  stress: { units: [["Pa", 0], ["MPa", 6], ["GPa", 9]], shown: "MPa" }, // a modulus too
  density: { units: [["kg/m³", 0], ["g/cm³", 3]] },
  area: { units: [["m²", 0], ["cm²", -4], ["mm²", -6]] },
  volume: { units: [["m³", 0], ["L", -3], ["cm³", -6]], shown: "L" },
  flow: { units: [["m³/s", 0], ["L/s", -3]], shown: "L/s" },
  stiffness: { units: [["N/m", 0], ["kN/m", 3], ["kN/mm", 6], ["MN/m", 6], ["GN/m", 9]] },
  contact_stiffness: { units: [["N/m^(1+α)", 0]] }, // its unit follows the exponent α
  damping: { units: [["N·s/m", 0], ["kN·s/m", 3], ["MN·s/m", 6]] },
  force: { units: [["N", 0], ["kN", 3], ["MN", 6]], shown: "kN" },
  time: { units: [["s", 0], ["ms", -3], ["µs", -6]], shown: "µs" },
  rate: { units: [["1/s", 0]] },
  frequency: { units: [["Hz", 0], ["kHz", 3], ["MHz", 6]], shown: "MHz" },
  slowness: { units: [["s/m", 0]] },
  energy: { units: [["J", 0]] },
  power: { units: [["W", 0], ["kW", 3]], shown: "kW" },
  ratio: { units: [["–", 0], ["%", -2]], shown: "%" },
  dimensionless: { units: [["", 0]] },
  depth: { units: [["m", 0]] }, // a pile's toe below the surface, a ram's stroke: in metres, as a site reads them
  blow_count: { units: [["blows/m", 0]] },
};
const POWER = new Map(Object.values(QUANTITIES).flatMap((q) => q.units));

// The names of the units `quantity` is offered in, the SI one first.
export const unitsOf = (quantity) => (QUANTITIES[quantity] || QUANTITIES.dimensionless).units.map(([unit]) => unit);

// The unit the views show `quantity` in.
export function shownUnit(quantity) {
  const q = QUANTITIES[quantity];
  return q.shown ?? q.units[0][0];
}

// The quantity whose SI unit is `unit` ("Pa": stress), if any.
export const quantityOfSI = (unit) => Object.keys(QUANTITIES).find((q) => QUANTITIES[q].units[0][0] === unit);

// An SI value as a number in `unit`: one rounding (v / 1e3, not v * 1e-3, which rounds twice).
export function inUnit(value, unit) {
  const power = POWER.get(unit) ?? 0;
  return power >= 0 ? value / 10 ** power : value * 10 ** -power;
}

// An SI value in the unit the views show `quantity` in.
export const shown = (value, quantity) => inUnit(value, shownUnit(quantity));

// `text`, a decimal number (3.5, -.2, 1e-3), times 10^`power`, as decimal text: the same digits
// with the point moved, so nothing is rounded. null when `text` is not a decimal number. Plain
// from 1e-4 to under 1e6, else with an exponent (2.1e11, 8.3e-7), as an engineer writes them.
export function shiftDecimal(text, power) {
  const match = /^([+-]?)(\d*)(?:\.(\d*))?(?:e([+-]?\d+))?$/i.exec(String(text).trim());
  if (!match || !(match[2] || match[3])) return null;
  const [, sign, whole, fraction = "", exponent = "0"] = match;
  let digits = whole + fraction;
  let point = whole.length + Number(exponent) + power; // the value is 0.<digits> × 10^point
  const leading = /^0*/.exec(digits)[0].length;
  digits = digits.slice(leading).replace(/0+$/, "");
  point -= leading;
  if (!digits) return "0";
  const minus = sign === "-" ? "-" : "";
  const first = point - 1; // the exponent of the first digit
  if (first < -4 || first > 5) return `${minus}${digits[0]}${digits.length > 1 ? `.${digits.slice(1)}` : ""}e${first}`;
  if (point <= 0) return `${minus}0.${"0".repeat(-point)}${digits}`;
  if (point >= digits.length) return `${minus}${digits}${"0".repeat(point - digits.length)}`;
  return `${minus}${digits.slice(0, point)}.${digits.slice(point)}`;
}

// The typed digits of a value in unit `from` re-expressed in unit `to`; null when not a number.
export const reexpressed = (text, from, to) => shiftDecimal(text, (POWER.get(from) ?? 0) - (POWER.get(to) ?? 0));

// The SI value of `text` typed in `unit` ("mm", "g/cm³"): a number, the double nearest the
// decimal typed; undefined when empty; the text itself when it is not a finite number, so that
// the service names it ("must be a number, not the string "abc"").
export function toSI(text, unit = "") {
  const trimmed = String(text).trim();
  if (!trimmed) return undefined;
  const shifted = shiftDecimal(trimmed, POWER.get(unit) ?? 0);
  const value = shifted === null ? NaN : Number(shifted);
  return Number.isFinite(value) ? value : trimmed;
}

// An SI value as shown in `unit`: exact, as toSI reads it back to the same double.
export function fromSI(value, unit = "") {
  if (value === undefined || value === null) return "";
  if (typeof value === "string") return value;
  if (typeof value !== "number") return JSON.stringify(value);
  if (!Number.isFinite(value)) return String(value);
  return shiftDecimal(String(value), -(POWER.get(unit) ?? 0));
}
