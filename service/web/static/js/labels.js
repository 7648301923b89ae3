// Names for people. The API's identifiers carry their unit as a suffix (confined_modulus_pa,
// bulk_density_kg_m3, normal_stress_pa) and the calibration's column keys join test, quantity and
// condition with "__" (cct__confined_modulus_pa__normal_stress_pa_24000); the page shows
// "confined modulus (Pa)" and "cct · confined modulus (Pa) at normal stress 24 kPa" instead, so no
// internal key reaches the text a user reads (issue 31).
import { fmt } from "./core.js";

// Longest suffix first: "_kg_m3" before "_m3"... and "_n_per_m" before "_m".
const UNITS = [["_kg_m3", "kg/m³"], ["_n_per_m", "N/m"], ["_j_m2", "J/m²"], ["_m_s", "m/s"], ["_pa", "Pa"], ["_deg", "deg"],
  ["_kg", "kg"], ["_mm", "mm"], ["_m", "m"], ["_n", "N"], ["_s", "s"]];
const TESTS = "fill|cct|dst|aor|anchor|battery";

// "bulk_density_kg_m3" -> { label: "bulk density", unit: "kg/m³" }; no known suffix: unit "".
export function nameAndUnit(name) {
  const text = String(name);
  const hit = UNITS.find(([suffix]) => text.endsWith(suffix) && text.length > suffix.length);
  const bare = hit ? text.slice(0, -hit[0].length) : text;
  return { label: bare.replaceAll("_", " "), unit: hit ? hit[1] : "" };
}

// "confined_modulus_pa" -> "confined modulus (Pa)"; "porosity" -> "porosity".
export function quantityLabel(name) {
  const { label, unit } = nameAndUnit(name);
  return unit ? `${label} (${unit})` : label;
}

// One value with its unit; stresses of a kPa or more in kPa, as the tests are run and reported.
export function withUnit(value, unit) {
  if (unit === "Pa" && Math.abs(value) >= 1000) return `${fmt(value / 1000, 4)} kPa`;
  return unit ? `${fmt(value, 4)} ${unit}` : fmt(value, 4);
}

// {normal_stress_pa: 24000} -> "normal stress 24 kPa"; several joined by ", "; none: "".
export function conditionText(condition) {
  return Object.entries(condition || {}).map(([name, value]) => {
    const { label, unit } = nameAndUnit(name);
    return `${label} ${withUnit(Number(value), unit)}`;
  }).join(", ");
}

// A target or response row ({test, quantity, condition}) in words:
// "dst · friction angle (deg)", "dst · residual shear stress (Pa) at normal stress 24 kPa".
export function targetLabel({ test, quantity, condition }) {
  const cond = conditionText(condition);
  return `${test} · ${quantityLabel(quantity)}${cond ? " at " + cond : ""}`;
}

// A column key (calibration/keys.py ResponseKey.name) back in words. Its conditions were written
// "{name}_{value:.6g}" with every character other than a letter, digit or "_" made "_": the value
// is the trailing number, its "." and an exponent's sign became "_" (read back as "." and "e+";
// conditions are stresses, heights and speeds, none below 1e-4).
export function keyText(key) {
  const [test, quantity, ...conditions] = String(key).split("__");
  const condition = {};
  for (const part of conditions) {
    const m = part.match(/^(.+?)_(\d+(?:_\d+)?(?:e_\d+)?)$/);
    if (!m) return `${test} · ${quantityLabel(quantity)} (${conditions.join(", ")})`;
    condition[m[1]] = Number(m[2].replace(/e_/, "e+").replace("_", "."));
  }
  return targetLabel({ test, quantity, condition });
}

// Any such key inside a sentence (a verdict, a diagnosis message, a model's error) in words.
const KEY_IN_TEXT = new RegExp(`\\b(?:${TESTS})__[a-z0-9_]+`, "g");
export function humanText(text) {
  return text === null || text === undefined ? text : String(text).replace(KEY_IN_TEXT, (key) => keyText(key));
}
