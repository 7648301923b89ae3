// Campaigns: the list, and the creation form that reaches what POST /campaigns accepts: targets
// picked from the material's measurements, factors (micro parameters or effect strengths), design,
// fixed parameters and contact effects, options, priors, constraints, automatic mode (the loop adds
// the indicated effects by itself, up to max_iterations).
import { api, condition, h, pageQuery, pager, schemas, status, submitForm, table } from "./core.js";
import { catalogue, effectPicker, pickedEffects } from "./effects.js";
import { evaluatorSelect, evaluators } from "./evaluators.js";
import { batteryChecks, batteryOptions, labTests, testSelect } from "./labtests.js";
import { numberInput, numberListField, readNumber, readNumberList } from "./numbers.js";

const DEFAULT_FACTORS = [["particle_density_kg_m3", 2300, 2700], ["particle_stiffness_n_per_m", 1.0e6, 3.0e6], ["friction_pp", 0.3, 1.0]];

function microNames(defs) {
  return Object.entries(defs.MicroParameters.properties).filter(([n, p]) => n !== "effects" && (p.type === "number" || (p.anyOf || []).some((a) => a.type === "number"))).map(([n]) => n);
}

function options(names, chosen) {
  return [h("option", { value: "" }, "—"), ...names.map((n) => h("option", { value: n, selected: n === chosen }, n))];
}

// A repeatable row whose inputs carry data-loc `${list}.${index}.${field}`; the row itself carries
// `${list}.${index}` (errors about the row as a whole, e.g. low >= high).
function rowList(list, makeRow, initial) {
  const box = h("div", { className: "rows", "data-list": list });
  const add = (values) => {
    const index = box.children.length;
    box.append(h("div", { className: "row", "data-loc": `${list}.${index}` }, makeRow(index, values || {})));
  };
  (initial.length ? initial : [{}]).forEach(add);
  return [box, h("button", { type: "button", className: "secondary small", onclick: () => add({}) }, "+ row")];
}

function field(label, input) { return h("label", {}, label, input); }

const MATERIAL_CHOICES = 200;  // GET /materials answers at most 200 a page (service.api.params.MaterialLimit)

export async function campaignsPage(view, params) {
  // the form's material choice lists the first MATERIAL_CHOICES materials (the listing's largest page)
  const [page, materialPage, effects, defs, backends, tests] = await Promise.all([api(`/campaigns?${pageQuery(params)}`),
    api(`/materials?limit=${MATERIAL_CHOICES}`), catalogue(), schemas(), evaluators(), labTests()]);
  const campaigns = page.items, materials = materialPage.items;
  const micro = microNames(defs);
  const factorNames = [...micro, ...effects.effects.flatMap((e) => e.parameters.map((p) => `effects.${e.name}.${p.name}`))];
  const chosen = params.get("material") || (materials.find((m) => m.bundled) || materials[0] || {}).id;
  const targetsBox = h("div", { className: "targets" });
  const materialSelect = h("select", { name: "material_id", "data-loc": "material_id" },
    materials.map((m) => h("option", { value: m.id, selected: String(m.id) === String(chosen) }, m.name)));
  const showTargets = () => {
    const material = materials.find((m) => String(m.id) === materialSelect.value);
    targetsBox.replaceChildren(...(material ? material.measurements.map((m, i) => h("label", { className: "check" },
      h("input", { type: "checkbox", name: "target", value: String(i), "data-loc": `targets.${i}` }),
      ` ${m.test} · ${m.quantity}${Object.keys(m.condition || {}).length ? " · " + condition(m.condition) : ""}`)) : []));
  };
  materialSelect.addEventListener("change", showTargets);
  showTargets();

  const [factorRows, addFactor] = rowList("factors", (i, v) => [
    field("Factor", h("select", { name: "factor_name", "data-loc": `factors.${i}.name` }, options(factorNames, v.name))),
    field("Low", numberInput({ name: "factor_low", value: v.low ?? "", "data-loc": `factors.${i}.low` })),
    field("High", numberInput({ name: "factor_high", value: v.high ?? "", "data-loc": `factors.${i}.high` })),
    h("label", { className: "check" }, h("input", { type: "checkbox", name: `factor_log_${i}`, "data-loc": `factors.${i}.log` }), " log scale")],
  DEFAULT_FACTORS.map(([name, low, high]) => ({ name, low, high })));
  const [fixedRows, addFixed] = rowList("fixed", (i, v) => [
    field("Fixed parameter", h("select", { name: "fixed_name", "data-loc": "fixed_parameters" }, options(micro, v.name))),
    // the API names a fixed parameter's error by the parameter (at the select); the page's own
    // refusal of what was typed names this box (a loc of the page's, no API field is called "value")
    field("Value (SI)", numberInput({ name: "fixed_value", "data-loc": `fixed_parameters.value.${i}` }))], []);
  const [priorRows, addPrior] = rowList("priors", (i) => [
    field("Prior on factor", h("select", { name: "prior_parameter", "data-loc": `priors.${i}.parameter` }, options(factorNames))),
    field("Value", numberInput({ name: "prior_value", "data-loc": `priors.${i}.value` })),
    field("Std. uncertainty", numberInput({ name: "prior_uncertainty", "data-loc": `priors.${i}.uncertainty` })),
    field("Source", h("input", { name: "prior_source", "data-loc": `priors.${i}.source` }))], []);

  const form = h("form", { className: "card", id: "new-campaign", novalidate: true }, h("h3", {}, "New campaign"),
    h("div", { className: "form-errors" }),
    h("div", {},
      field("Name", h("input", { name: "name", value: "calibration", "data-loc": "name" })),
      field("Material", materialSelect),
      field("Evaluator", evaluatorSelect(backends, defs.CampaignCreate)),
      field("Fidelity", h("select", { name: "fidelity", "data-loc": "fidelity" }, h("option", {}, "screening"), h("option", {}, "thesis"))),
      field("Resolution", h("select", { name: "resolution", "data-loc": "resolution",
        title: "as measured / coarse: the material's particles in the rig its measurements were made in (fidelity is then unused)" },
        h("option", { value: "" }, "the fidelity's preset"), h("option", { value: "as_measured" }, "as measured"),
        h("option", { value: "coarse" }, "coarse"))),
      field("Coarse size factor", numberInput({ name: "scale_factor", placeholder: "proposed", "data-loc": "resolution.scale_factor" })),
      field("Each run simulates", testSelect(tests, "test")),
      field("Seed", h("input", { name: "seed", type: "number", value: 0, "data-loc": "seed" })),
      field("Priority", h("input", { name: "priority", type: "number", value: 0, "data-loc": "priority" }))),
    h("h4", {}, "Targets"), h("p", { className: "muted" }, "None ticked: every measurement the runs simulate."), targetsBox,
    h("h4", {}, "Factors (design box)"), factorRows, addFactor,
    h("h4", {}, "Design"),
    h("div", {},
      field("Type", h("select", { name: "design_type", "data-loc": "design.type" }, h("option", {}, "full"), h("option", {}, "fractional"))),
      field("Generators (fractional)", h("input", { name: "generators", placeholder: "D=ABC", "data-loc": "design.generators" })),
      field("Centre runs", h("input", { name: "centre_runs", type: "number", value: 3, "data-loc": "design.centre_runs" })),
      field("Replicates", h("input", { name: "replicates", type: "number", value: 1, "data-loc": "design.replicates" }))),
    h("h4", {}, "Fixed parameters and contact effects"), fixedRows, addFixed,
    effectPicker(effects.effects, "fixed_parameters.effects"),
    h("h4", {}, "Options"),
    h("div", {},
      numberListField("DST normal stresses (kPa)", "dst_kpa", "options.dst_normal_stresses_pa", "fidelity default"),
      batteryChecks(tests, () => "options"),
      field("Assumed relative uncertainty", numberInput({ name: "default_relative_uncertainty", value: 0.05, "data-loc": "default_relative_uncertainty" })),
      h("label", { className: "check" }, h("input", { type: "checkbox", name: "allow_extrapolation", "data-loc": "allow_extrapolation" }), " allow the optimum outside the box"),
      h("label", { className: "check" }, h("input", { type: "checkbox", name: "diagnose", checked: true, "data-loc": "diagnose" }), " diagnose a missing effect when the model misses"),
      h("label", { className: "check", title: "also after a report that passes with nothing flagged: the candidates' directed test sees a misfit spread thinly over many targets; one battery per candidate and a baseline, per confirmation seed" },
        h("input", { type: "checkbox", name: "diagnose_always", "data-loc": "diagnose_always" }), " diagnose after every report"),
      h("label", { className: "check", title: "after each iteration, add the effect the diagnosis indicates and run the next one, until the lack of fit passes, nothing improves, or the maximum is reached" },
        h("input", { type: "checkbox", name: "automatic", "data-loc": "automatic" }), " automatic mode"),
      field("Max. iterations (automatic)", h("input", { name: "max_iterations", type: "number", value: 4, "data-loc": "max_iterations" })),
      field("Confirmation seeds (batteries at each optimum)", h("input", { name: "confirmation_seeds", type: "number", value: 2, min: 1, "data-loc": "confirmation_seeds",
        title: "the report compares their mean with the measurements: more seeds average the simulator's scatter down" }))),
    h("h4", {}, "Priors (directly measured factors)"), priorRows, addPrior,
    h("h4", {}, "Constraints"),
    field("One per line, e.g. friction_pw <= friction_pp", h("textarea", { name: "constraints", rows: 2, "data-loc": "constraints" })),
    h("p", {}, h("button", { type: "submit" }, "Create (draft)")));

  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const material = materials.find((m) => String(m.id) === materialSelect.value);
    // the body is read inside the submission, so that a list typed wrongly is shown beside its field
    const made = await submitForm(form, () => api("/campaigns", { method: "POST", body: campaignBody(form, material, tests) }));
    if (made) location.hash = `#/campaigns/${made.id}`;
  });
  view.replaceChildren(h("h2", {}, `Campaigns (${page.total})`),
    h("div", { className: "scroll" }, table(["Id", "Name", "Material", "Evaluator", "Status", "Iteration", "Phase", "Runs", "Owner"],
      campaigns.map((c) => [h("a", { href: `#/campaigns/${c.id}` }, `#${c.id}`), c.name, String(c.material_id), c.evaluator,
        status(c.status), String(c.current_iteration), c.phase || "–", `${c.runs_succeeded}/${c.runs_total}`, c.owner || "–"]))),
    pager(page, params, "/campaigns"),
    materialPage.total > materials.length ? h("p", { className: "muted" }, `The form lists the first ${materials.length} of ${materialPage.total} materials.`) : "",
    form);
  return campaigns.some((c) => c.status === "running");
}

// The request body, field by field as CampaignCreate names them; numbers stay as typed (the API
// validates and names the field), empty optional inputs are left out.
function campaignBody(form, material, tests) {
  const data = new FormData(form);
  const all = (name) => data.getAll(name).map(String);
  const num = (v) => (v === "" || v === null ? null : Number(v));
  // real numbers by the page's one rule (numbers.js: "0,5" is 0.5), a refusal placed at `loc`
  const real = (v, loc) => readNumber(v, loc);
  const factors = all("factor_name").map((name, i) => ({ name, low: real(all("factor_low")[i], `factors.${i}.low`),
    high: real(all("factor_high")[i], `factors.${i}.high`), log: data.get(`factor_log_${i}`) === "on" })).filter((f) => f.name);
  const fixed = {};
  all("fixed_name").forEach((name, i) => { if (name) fixed[name] = real(all("fixed_value")[i], `fixed_parameters.value.${i}`); });
  const effects = pickedEffects(form);
  if (Object.keys(effects).length) fixed.effects = effects;
  const priors = all("prior_parameter").map((parameter, i) => ({ parameter, value: real(all("prior_value")[i], `priors.${i}.value`),
    uncertainty: real(all("prior_uncertainty")[i], `priors.${i}.uncertainty`), source: all("prior_source")[i] })).filter((p) => p.parameter);
  const generators = String(data.get("generators") || "").split(",").map((g) => g.trim()).filter(Boolean);
  const options = batteryOptions(tests, data);
  const dst = readNumberList(data.get("dst_kpa"), "options.dst_normal_stresses_pa");
  if (dst.length) options.dst_normal_stresses_pa = dst.map((kpa) => kpa * 1000);
  const ticked = all("target").map(Number);
  const targets = material && ticked.length
    ? ticked.map((i) => material.measurements[i]).map((m) => ({ test: m.test, quantity: m.quantity, condition: m.condition || {} }))
    : null;
  const mode = data.get("resolution");
  const factor = String(data.get("scale_factor") || "").trim();
  const resolution = !mode ? null
    : mode === "coarse" && factor ? { mode, scale_factor: real(factor, "resolution.scale_factor") } : mode;
  return {
    name: data.get("name"), material_id: num(data.get("material_id")), evaluator: data.get("evaluator"),
    fidelity: data.get("fidelity"), ...(resolution ? { resolution } : {}), test: data.get("test"), seed: num(data.get("seed")), priority: num(data.get("priority")),
    factors, targets, fixed_parameters: fixed, options, priors,
    design: { type: data.get("design_type"), centre_runs: num(data.get("centre_runs")), replicates: num(data.get("replicates")),
      ...(generators.length ? { generators } : {}) },
    default_relative_uncertainty: real(data.get("default_relative_uncertainty"), "default_relative_uncertainty"),
    allow_extrapolation: data.get("allow_extrapolation") === "on", diagnose: data.get("diagnose") === "on",
    diagnose_always: data.get("diagnose_always") === "on",
    automatic: data.get("automatic") === "on", max_iterations: num(data.get("max_iterations")),
    confirmation_seeds: num(data.get("confirmation_seeds")),
    constraints: String(data.get("constraints") || "").split("\n").map((c) => c.trim()).filter(Boolean),
  };
}
