// Materials: list, measurements (SI, with replicates and uncertainty), adding measurements in any accepted unit.
import { api, attempt, condition, flash, fmt, h, pageQuery, pager, submitForm, table } from "./core.js";
import { nameAndUnit } from "./labels.js";
import { refresh } from "./live.js";
import { numberInput, numberListField, readNumber, readNumberList } from "./numbers.js";

export async function materialsPage(view, params = new URLSearchParams()) {
  const page = await api(`/materials?${pageQuery(params)}`);
  const materials = page.items;
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
  view.replaceChildren(h("h2", {}, `Materials (${page.total})`),
    table(["Id", "Name", "Measurements", "Bundled", "Owner", "Description"],
      materials.map((m) => [String(m.id), h("a", { href: `#/materials/${m.id}` }, m.name), String(m.measurements.length),
        m.bundled ? "yes" : "no", m.owner || "–", m.description])), pager(page, params, "/materials"), form);
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
  testSelect.dataset.loc = "test"; quantitySelect.dataset.loc = "quantity"; unitSelect.dataset.loc = "unit";
  const form = h("form", { className: "card", id: "add-measurement", novalidate: true }, h("h3", {}, "Add a measurement"),
    h("div", { className: "form-errors" }),
    h("label", {}, "Test", testSelect), h("label", {}, "Quantity", quantitySelect), h("label", {}, "Unit", unitSelect),
    numberListField("Replicate values", "values", "values", "1412.0; 1383.6; 1397.8"),
    h("label", {}, "Condition name", h("input", { name: "cond_name", placeholder: "normal_stress_pa", "data-loc": "condition" })),
    h("label", {}, "Condition value", numberInput({ name: "cond_value", "data-loc": "condition" })),
    h("label", {}, "Condition unit", h("input", { name: "cond_unit", placeholder: "kPa", "data-loc": "condition_units" })),
    h("label", {}, "Source", h("input", { name: "source", "data-loc": "source" })),
    h("button", { type: "submit" }, "Add"));
  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const data = new FormData(form);
    const body = () => {  // inside the submission: a list typed wrongly is shown beside its field
      const out = { test: data.get("test"), quantity: data.get("quantity"), unit: data.get("unit"), source: data.get("source"),
        values: readNumberList(data.get("values"), "values") };
      const name = String(data.get("cond_name") || "").trim();
      if (name) {
        out.condition = { [name]: readNumber(data.get("cond_value"), "condition") };
        if (data.get("cond_unit")) out.condition_units = { [name]: data.get("cond_unit") };
      }
      return out;
    };
    const added = await submitForm(form, () => api(`/materials/${id}/measurements`, { method: "POST", body: body() }));
    if (added) {
      // stored, but outside what granular materials measure: say which unit it was likely meant in
      const doubts = added.warnings || [];
      flash(doubts.length ? `measurement added, but check it: ${doubts.join(" ")}` : "measurement added", doubts.length ? "warning" : "ok");
      refresh();
    }
  });
  view.replaceChildren(h("h2", {}, material.name), h("p", { className: "muted" }, material.description),
    h("p", { className: "muted" }, material.source),
    material.rig ? h("p", { className: "rig" }, "Measured in rig ", h("a", { href: `#/rigs/${material.rig_id}` }, material.rig)) : "",
    ...(material.warnings || []).map((w) => h("p", { className: "warning" }, `warning: ${w}`)),
    h("h3", {}, "Measurements (SI)"),
    table(["Test", "Quantity", "Condition", "n", "Mean", "Std. uncertainty", "Unit", "Replicates", "Source", ""],
      material.measurements.map((m) => [m.test, m.quantity, condition(m.condition),
        m.reported_replicates ? `${m.n} (avg of ${m.reported_replicates})` : String(m.n), m.mean, m.standard_uncertainty, m.unit,
        m.values.map((v) => (v === null ? "n/a" : Number(v.toPrecision(5)))).join(", "), m.source,
        material.bundled ? "" : h("button", { className: "secondary", onclick: async () => {
          if (!window.confirm(`Delete the ${m.test} ${m.quantity} measurement (${m.n} values)?`)) return;
          if (await attempt(() => api(`/materials/${id}/measurements/${m.id}`, { method: "DELETE" }), "deleted")) refresh();
        } }, "Delete")])),
    Object.keys(material.direct_estimates || {}).length ? h("div", { className: "direct-estimates" }, h("h3", {}, "Direct estimates"),
      estimatesTable(material.direct_estimates)) : "",
    material.bundled ? readOnlyNote(view, material) : form,
    h("p", {}, h("a", { href: `#/campaigns?material=${id}` }, "Calibrate this material →")));
}

// The material's direct estimates (measured directly, not calibrated): one row each, named for
// people, with its unit and source. An entry is a number, a list (the loads a test was run at), a
// {value, source} record, or a table of named values (friction against each wall material).
function estimatesTable(estimates) {
  const values = (v) => (Array.isArray(v) ? v.map((x) => fmt(x)).join(", ")
    : v && typeof v === "object" ? Object.entries(v).map(([k, x]) => `${k} ${fmt(x)}`).join("; ") : fmt(v));
  return h("div", { className: "scroll" }, table(["Estimate", "Value", "Unit", "Source"],
    Object.entries(estimates).map(([name, entry]) => {
      const record = entry && typeof entry === "object" && !Array.isArray(entry) && "value" in entry;
      const { label, unit } = nameAndUnit(name);
      return [label, values(record ? entry.value : entry), unit || "–", record ? entry.source || "–" : "–"];
    })));
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
