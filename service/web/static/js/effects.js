// The contact-effect picker shared by job submission and campaign creation: one checkbox per effect
// of GET /api/v1/effects with its parameters (units and bounds in the tooltip). The chosen effects
// become parameters.effects = {name: {parameter: value}} (jobs) or fixed_parameters.effects (campaigns).
import { api, h } from "./core.js";
import { numberInput, readNumber } from "./numbers.js";

let catalogueCache = null;
export async function catalogue() {
  if (!catalogueCache) catalogueCache = await api("/effects");
  return catalogueCache;
}

function bounds(p) {
  const lo = p.minimum ?? p.exclusiveMinimum, hi = p.maximum ?? p.exclusiveMaximum;
  return lo === undefined && hi === undefined ? "" : ` [${lo ?? "-inf"}, ${hi ?? "inf"}]`;
}

// locPrefix: where the API reports errors of these inputs, e.g. "parameters.effects".
export function effectPicker(effects, locPrefix) {
  return h("fieldset", { className: "effects" }, h("legend", {}, "Contact effects"),
    effects.map((e) => h("div", { className: "effect" },
      h("label", { className: "check", title: e.description },
        h("input", { type: "checkbox", name: "effect", value: e.name, "data-loc": `${locPrefix}.${e.name}` }),
        ` ${e.candidate?.title || e.name} `, h("code", {}, e.name)),
      e.parameters.map((p) => h("label", { title: `${p.description}${bounds(p)}` }, p.name,
        numberInput({ name: `effect:${e.name}:${p.name}`, value: p.default ?? "", "data-loc": `${locPrefix}.${e.name}.${p.name}` }))))));
}

// {name: {parameter: value}} for the ticked effects; empty inputs are left to the effect's defaults.
// Numbers are read by the page's one rule (numbers.js); a refusal names the box (its data-loc).
export function pickedEffects(form) {
  const ticked = new FormData(form).getAll("effect");
  const out = Object.fromEntries(ticked.map((name) => [name, {}]));
  for (const input of form.querySelectorAll("input[name^='effect:']")) {
    const [, effect, param] = input.name.split(":");
    if (!(effect in out)) continue;
    const value = readNumber(input.value, input.dataset.loc);
    if (value !== null) out[effect][param] = value;
  }
  return out;
}
