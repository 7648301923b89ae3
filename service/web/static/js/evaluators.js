// The evaluator select shared by job submission and campaign creation: one option per backend of
// GET /api/v1/evaluators (the registry, calibration/evaluator_registry.py), labelled "name (title)",
// the form's default (from its OpenAPI schema) chosen.
import { api, h } from "./core.js";

let listCache = null;
export async function evaluators() {
  if (!listCache) listCache = (await api("/evaluators")).evaluators;
  return listCache;
}

// schema: the form's component in the OpenAPI document (JobSubmit, CampaignCreate); its evaluator
// default is the option first chosen.
export function evaluatorSelect(list, schema) {
  const chosen = schema?.properties?.evaluator?.default;
  return h("select", { name: "evaluator", "data-loc": "evaluator" },
    list.map((e) => h("option", { value: e.name, selected: e.name === chosen, title: e.description }, `${e.name} (${e.title})`)));
}
