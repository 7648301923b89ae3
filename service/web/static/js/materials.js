// Materials: list, measurements (SI, with replicates and uncertainty), adding measurements in any accepted unit.
import { api, attempt, condition, h, table } from "./core.js";
import { refresh } from "./live.js";

export async function materialsPage(view) {
  const materials = await api("/materials");
  const form = h("form", { className: "card" }, h("h3", {}, "New material"),
    h("label", {}, "Name", h("input", { name: "name", required: true })),
    h("label", {}, "Description", h("input", { name: "description" })),
    h("button", { type: "submit" }, "Create"));
  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const data = new FormData(form);
    const made = await attempt(() => api("/materials", { method: "POST", body: { name: data.get("name"), description: data.get("description") } }));
    if (made) location.hash = `#/materials/${made.id}`;
  });
  view.replaceChildren(h("h2", {}, "Materials"),
    table(["Id", "Name", "Measurements", "Bundled", "Description"],
      materials.map((m) => [String(m.id), h("a", { href: `#/materials/${m.id}` }, m.name), String(m.measurements.length),
        m.bundled ? "yes" : "no", m.description])), form);
}

export async function materialPage(view, id) {
  const [material, quantities] = await Promise.all([api(`/materials/${id}`), api("/materials/quantities")]);
  const testSelect = h("select", { name: "test" }, Object.keys(quantities).map((t) => h("option", {}, t)));
  const quantitySelect = h("select", { name: "quantity" });
  const unitSelect = h("select", { name: "unit" });
  const fillQuantities = () => {
    quantitySelect.replaceChildren(...Object.keys(quantities[testSelect.value]).map((q) => h("option", {}, q)));
    fillUnits();
  };
  const fillUnits = () => {
    const info = quantities[testSelect.value][quantitySelect.value];
    unitSelect.replaceChildren(...info.accepted_units.map((u) => h("option", { selected: u === info.si_unit }, u)));
  };
  testSelect.addEventListener("change", fillQuantities);
  quantitySelect.addEventListener("change", fillUnits);
  fillQuantities();
  const form = h("form", { className: "card" }, h("h3", {}, "Add a measurement"),
    h("label", {}, "Test", testSelect), h("label", {}, "Quantity", quantitySelect), h("label", {}, "Unit", unitSelect),
    h("label", {}, "Replicate values (comma-separated)", h("input", { name: "values", required: true, placeholder: "1412.0, 1383.6, 1397.8" })),
    h("label", {}, "Condition name", h("input", { name: "cond_name", placeholder: "normal_stress_pa" })),
    h("label", {}, "Condition value", h("input", { name: "cond_value", type: "number", step: "any" })),
    h("label", {}, "Condition unit", h("input", { name: "cond_unit", placeholder: "kPa" })),
    h("label", {}, "Source", h("input", { name: "source" })),
    h("button", { type: "submit" }, "Add"));
  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const data = new FormData(form);
    const body = { test: data.get("test"), quantity: data.get("quantity"), unit: data.get("unit"), source: data.get("source"),
      values: String(data.get("values")).split(",").map((v) => v.trim()).filter(Boolean).map(Number) };
    const name = String(data.get("cond_name") || "").trim();
    if (name) {
      body.condition = { [name]: Number(data.get("cond_value")) };
      if (data.get("cond_unit")) body.condition_units = { [name]: data.get("cond_unit") };
    }
    if (await attempt(() => api(`/materials/${id}/measurements`, { method: "POST", body }), "measurement added")) refresh();
  });
  view.replaceChildren(h("h2", {}, material.name), h("p", { className: "muted" }, material.description),
    h("p", { className: "muted" }, material.source),
    h("h3", {}, "Measurements (SI)"),
    table(["Test", "Quantity", "Condition", "n", "Mean", "Std. uncertainty", "Unit", "Replicates", "Source", ""],
      material.measurements.map((m) => [m.test, m.quantity, condition(m.condition),
        m.reported_replicates ? `${m.n} (avg of ${m.reported_replicates})` : String(m.n), m.mean, m.standard_uncertainty, m.unit,
        m.values.map((v) => (v === null ? "n/a" : Number(v.toPrecision(5)))).join(", "), m.source,
        material.bundled ? "" : h("button", { className: "secondary", onclick: async () => {
          if (!window.confirm(`Delete the ${m.test} ${m.quantity} measurement (${m.n} values)?`)) return;
          if (await attempt(() => api(`/materials/${id}/measurements/${m.id}`, { method: "DELETE" }), "deleted")) refresh();
        } }, "Delete")])),
    Object.keys(material.direct_estimates || {}).length ? h("div", {}, h("h3", {}, "Direct estimates"),
      h("pre", {}, JSON.stringify(material.direct_estimates, null, 1))) : "",
    material.bundled ? readOnlyNote(view, material) : form,
    h("p", {}, h("a", { href: `#/campaigns?material=${id}` }, "Calibrate this material →")));
}

// The bundled reference material is read-only (the API answers 409): offer a copy to edit instead.
function readOnlyNote(view, material) {
  return h("p", { className: "muted" }, "Bundled reference data, read-only. ",
    h("button", { className: "secondary", onclick: async () => {
      const name = window.prompt("Name of the editable copy", `${material.name} (copy)`);
      if (!name) return;
      const copy = await attempt(() => api(`/materials/${material.id}/copy`, { method: "POST", body: { name } }), "copied");
      if (copy) location.hash = `#/materials/${copy.id}`;
    } }, "Copy to edit"));
}
