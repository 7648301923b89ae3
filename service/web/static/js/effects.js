// The contact-effect picker shared by job submission and campaign creation: one checkbox per effect
// of GET /api/v1/effects with its parameters (units and bounds in the tooltip). The chosen effects
// become parameters.effects = {name: {parameter: value}} (jobs) or fixed_parameters.effects (campaigns).
import { api, h } from "./core.js";

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
        h("input", { name: `effect:${e.name}:${p.name}`, type: "number", step: "any", value: p.default ?? "",
          "data-loc": `${locPrefix}.${e.name}.${p.name}` }))))));
}

// {name: {parameter: value}} for the ticked effects; empty inputs are left to the effect's defaults.
export function pickedEffects(form) {
  const data = new FormData(form);
  const out = {};
  for (const name of data.getAll("effect")) {
    out[name] = {};
    for (const [key, raw] of data.entries()) {
      const [tag, effect, param] = key.split(":");
      if (tag === "effect" && effect === name && raw !== "") out[name][param] = Number(raw);
    }
  }
  return out;
}
