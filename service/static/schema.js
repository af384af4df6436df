// The case's fields as its JSON schema says them, the schema the API publishes (/openapi.json,
// built from solver/case.py): the form is made from it.
import { getJSON } from "./api.js";

// Every field and group of the case by its path ("" the case itself, "tool.length"):
//   a field: {path, kind: "number", "whole", "text", "choice", "bool" or "table", title, quantity,
//             symbol, default, implied, bounds: {minimum, maximum, exclusiveMinimum, exclusiveMaximum},
//             choices: [[value, label]] of a choice};
//   a group: {path, kind: "group", keys: its fields' keys in the schema's order, and for one of
//             several kinds (a medium, a force) kinds: {kind: its fields' keys}, choices: [[kind, label]]}.
export async function caseFields() {
  const { components: { schemas } } = await getJSON("/openapi.json", { askKey: false });
  const fields = new Map();
  group(schemas, schemas.Case, "", fields);
  return fields;
}

const deref = (schemas, node) => (node.$ref ? schemas[node.$ref.split("/").at(-1)] : node);

// A property's own schema, its `anyOf [it, null]` unwrapped; the property's keys (its title,
// default, symbol) over the type's (its bounds, quantity).
function unwrap(schemas, property) {
  const { anyOf, ...outer } = property;
  const options = (anyOf || [property]).filter((node) => node.type !== "null");
  return { node: { ...deref(schemas, options[0]), ...(anyOf ? outer : {}) }, nullable: Boolean(anyOf) };
}

const labelled = (values, choices = {}) => values.map((value) => [value, choices[String(value)] ?? String(value)]);

function group(schemas, node, path, fields) {
  const variants = node.oneOf ? node.oneOf.map((variant) => deref(schemas, variant)) : [node];
  // A union's fields are every variant's, in the order they first come.
  const properties = Object.assign({}, ...variants.map((variant) => variant.properties));
  const entry = { path, kind: "group", keys: Object.keys(properties) };
  if (node.discriminator) {
    const tag = node.discriminator.propertyName;
    const kindOf = (variant) => variant.properties[tag].const;
    entry.kinds = Object.fromEntries(variants.map((v) => [kindOf(v), Object.keys(v.properties).filter((k) => k !== tag)]));
    entry.choices = variants.map((v) => labelled([kindOf(v)], v.properties[tag].choices)[0]);
  } else if (node.kind_fields) {
    entry.kinds = node.kind_fields;
    entry.choices = labelled(properties.kind.enum, properties.kind.choices);
  }
  fields.set(path, entry);
  for (const [key, property] of Object.entries(properties)) {
    const child = path ? `${path}.${key}` : key;
    const { node: inner, nullable } = unwrap(schemas, property);
    if (inner.properties || inner.oneOf) group(schemas, inner, child, fields);
    else fields.set(child, leaf(schemas, inner, nullable, child));
  }
}

function leaf(schemas, node, nullable, path) {
  const items = node.items ? deref(schemas, node.items) : {};
  const { minimum, maximum, exclusiveMinimum, exclusiveMaximum } = node;
  const field = {
    path, kind: kindOf(node, nullable), title: node.title, quantity: node.quantity ?? items.quantity,
    symbol: node.symbol, default: node.default ?? undefined, implied: node.implied,
    bounds: { minimum, maximum, exclusiveMinimum, exclusiveMaximum },
  };
  if (field.kind === "choice") field.choices = labelled(node.enum ?? (node.type === "boolean" ? [true, false] : [node.const]), node.choices);
  return field;
}

function kindOf(node, nullable) {
  if (node.enum || node.const !== undefined) return "choice";
  if (node.type === "boolean") return nullable ? "choice" : "bool"; // unset, true or false
  if (node.type === "integer") return "whole";
  if (node.type === "number") return "number";
  if (node.type === "array") return "table";
  return "text";
}
