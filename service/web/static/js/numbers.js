// Lists of numbers as people type them (replicate values, DST normal stresses, ...): one rule for
// every list field of the page, so that "1397,8" is one value 1397.8 everywhere and never two
// replicates 1397 and 8 (issue 31).
//
// The rule (LIST_HINT says it in the fields' hints):
//   - values are separated by semicolons, spaces or new lines; a comma followed by a space
//     ("1412, 1383") separates too, so lists written the usual English way still read;
//   - a comma inside a number is its decimal comma: "1397,8" is 1397.8, "0,125" is 0.125, but only
//     when the field uses no comma as a separator ("12,5, 24" is refused: 12.5 and 24, or 12, 5, 24?);
//   - what could be read two ways is refused, naming the value: a number with both "." and ","
//     ("1.397,8", "1,397.8"), with more than one comma ("1,397,8" or "6,12,24" meant as a list),
//     or whose comma could be a thousands separator: one to three leading digits, not all zeros, then
//     exactly three ("1,397": 1397 or 1.397?); "0,125" and "1397,800" are decimals.
// The CLI applies the same rule (service/materials/replicates.py); both are tested on the cases of
// tests/service/data/number_lists.json.
// Exponents are accepted ("1e8", "2,5e6"). The boxes for one real number (numberInput, read by
// readNumber) follow the same rule for a single value, so "0,5" means 0.5 in every field of the page.
import { ApiError, h } from "./core.js";

export const LIST_HINT = "separate values with ; or spaces; a comma inside a number is a decimal comma (1397,8)";

const NUMBER = /^[+-]?(\d+(\.\d*)?|\.\d+)(e[+-]?\d+)?$/i;
const SEPARATORS = /[;\s]+|,(?=\s)/;

// One typed value -> [number, null] or [null, why it is refused].
function parseValue(raw, commaSeparates) {
  const commas = (raw.match(/,/g) || []).length;
  if (commas && raw.includes(".")) return [null, `"${raw}" has both "." and ","; write it with one decimal mark`];
  if (commas && commaSeparates) return [null, `"${raw}": the list also separates values with ", ", so this comma could be either; separate values with ; or spaces, or write a decimal point`];
  if (commas > 1) return [null, `"${raw}" has more than one comma; separate values with ; or spaces`];
  if (commas === 1) {
    const [whole, rest] = raw.split(",");
    if (/^\d{3}$/.test(rest) && /^[+-]?0*[1-9]\d{0,2}$/.test(whole)) {
      return [null, `"${raw}" could be ${whole}${rest} or ${whole}.${rest}; write it without the comma or with a decimal point`];
    }
  }
  const text = raw.replace(",", ".");
  if (!NUMBER.test(text)) return [null, `"${raw}" is not a number`];
  if (!Number.isFinite(Number(text))) return [null, `"${raw}" is not a finite number`];
  return [Number(text), null];
}

// text -> { values: [numbers], error: null } or { values: null, error: message }; empty text gives [].
export function parseNumberList(text) {
  const commaSeparates = /,(\s|$)/.test(String(text ?? "").trim());
  const tokens = String(text ?? "").trim().split(SEPARATORS).map((t) => t.replace(/,+$/, "")).filter(Boolean);
  const values = [];
  for (const token of tokens) {
    const [value, error] = parseValue(token, commaSeparates);
    if (error) return { values: null, error };
    values.push(value);
  }
  return { values, error: null };
}

// The list typed in a form field, or a 422-shaped error at the field's data-loc, so that
// submitForm draws it beside the field like the API's own refusals.
export function readNumberList(text, loc) {
  const { values, error } = parseNumberList(text);
  if (error) throw new ApiError(422, [{ loc: ["body", ...loc.split(".")], msg: error }]);
  return values;
}

// One number typed in a box, by the same rule ("0,5" is 0.5); an empty box is null (not given).
export function readNumber(text, loc) {
  const values = readNumberList(text, loc);
  if (values.length > 1) throw new ApiError(422, [{ loc: ["body", ...loc.split(".")], msg: `one number here, not ${values.length}` }]);
  return values.length ? values[0] : null;
}

// A box for one real number. Text, not type="number": Chromium's number box drops a typed comma,
// so "0,5" became 05 = 5 without a word; here it is read by the rule above.
export function numberInput(attrs) {
  return h("input", { ...attrs, type: "text", inputmode: "decimal", autocomplete: "off" });
}

// A list field: its label, the input (data-loc: where the API reports its errors) and the rule as
// a hint under it, so the rule is read where the list is typed.
export function numberListField(label, name, loc, placeholder = "") {
  return h("label", {}, label, h("input", { name, placeholder, "data-loc": loc, inputmode: "decimal", autocomplete: "off" }),
    h("span", { className: "hint" }, LIST_HINT));
}
