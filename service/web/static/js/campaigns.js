// Campaigns: create (factors, design, targets), drive (start/pause/resume), and read the report.
import { api, attempt, condition, fmt, h, status, table } from "./core.js";
import { targetChart } from "./charts.js";

const FACTORS = [
  ["particle_density_kg_m3", 2300, 2700], ["particle_stiffness_n_per_m", 1.0e6, 3.0e6], ["friction_pp", 0.3, 1.0],
  ["friction_pw", 0.3, 0.9], ["shear_to_normal_stiffness_ratio", 0.5, 1.0], ["damping_ratio", 0.2, 0.8],
];

function factorRow(name = "", low = "", high = "") {
  return h("div", { className: "factor" },
    h("label", {}, "Factor", h("select", { name: "factor" }, h("option", { value: "" }, "—"),
      FACTORS.map(([n]) => h("option", { selected: n === name }, n)))),
    h("label", {}, "Low", h("input", { name: "low", type: "number", step: "any", value: low })),
    h("label", {}, "High", h("input", { name: "high", type: "number", step: "any", value: high })));
}

export async function campaignsPage(view, params) {
  const [campaigns, materials] = await Promise.all([api("/campaigns"), api("/materials")]);
  const chosen = params.get("material");
  const form = h("form", { className: "card" }, h("h3", {}, "New campaign"),
    h("div", {},
      h("label", {}, "Name", h("input", { name: "name", required: true, value: "calibration" })),
      h("label", {}, "Material", h("select", { name: "material_id" }, materials.map((m) => h("option", { value: m.id, selected: String(m.id) === chosen }, m.name)))),
      h("label", {}, "Evaluator", h("select", { name: "evaluator" }, h("option", {}, "analytic"), h("option", {}, "dem"))),
      h("label", {}, "Fidelity", h("select", { name: "fidelity" }, h("option", {}, "screening"), h("option", {}, "thesis"))),
      h("label", {}, "Seed", h("input", { name: "seed", type: "number", min: 0, value: 0 }))),
    h("div", { id: "factors" }, FACTORS.slice(0, 3).map(([n, lo, hi]) => factorRow(n, lo, hi)), factorRow()),
    h("div", {},
      h("label", {}, "Design", h("select", { name: "type" }, h("option", {}, "full"), h("option", {}, "fractional"))),
      h("label", {}, "Generators", h("input", { name: "generators", placeholder: "D=ABC" })),
      h("label", {}, "Centre runs", h("input", { name: "centre_runs", type: "number", min: 0, value: 3 }))),
    h("button", { type: "submit" }, "Create (draft)"));
  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const data = new FormData(form);
    const names = data.getAll("factor"), lows = data.getAll("low"), highs = data.getAll("high");
    const factors = names.map((name, i) => ({ name, low: Number(lows[i]), high: Number(highs[i]) })).filter((f) => f.name);
    const generators = String(data.get("generators") || "").split(",").map((g) => g.trim()).filter(Boolean);
    const body = { name: data.get("name"), material_id: Number(data.get("material_id")), evaluator: data.get("evaluator"),
      fidelity: data.get("fidelity"), seed: Number(data.get("seed")), factors,
      design: { type: data.get("type"), centre_runs: Number(data.get("centre_runs")), ...(generators.length ? { generators } : {}) } };
    const made = await attempt(() => api("/campaigns", { method: "POST", body }));
    if (made) location.hash = `#/campaigns/${made.id}`;
  });
  view.replaceChildren(h("h2", {}, "Campaigns"),
    table(["Id", "Name", "Material", "Evaluator", "Status", "Iteration", "Phase", "Runs"],
      campaigns.map((c) => [h("a", { href: `#/campaigns/${c.id}` }, `#${c.id}`), c.name, String(c.material_id), c.evaluator,
        status(c.status), String(c.current_iteration), c.phase || "–", `${c.runs_succeeded}/${c.runs_total}`])), form);
  return campaigns.some((c) => c.status === "running");
}

function reportSection(report) {
  const rows = report.targets;
  return h("section", { className: "card" },
    h("h3", {}, `Report: `, status(report.verdict.replaceAll(" ", "_")), ` ${report.verdict}`),
    table(["Test", "Quantity", "Condition", "Measured ± u", "Predicted [95% PI]", "Confirmed", "z (confirmed)", "Reachability (min |z|)", "Status"],
      rows.map((r) => [r.test, r.quantity, condition(r.condition),
        r.measured_uncertainty ? `${fmt(r.measured)} ± ${fmt(r.measured_uncertainty, 3)}${r.uncertainty_assumed ? " (assumed)" : ""}` : fmt(r.measured),
        r.predicted !== undefined ? `${fmt(r.predicted)} [${fmt(r.prediction_interval?.[0])}, ${fmt(r.prediction_interval?.[1])}]` : "–",
        r.confirmed !== undefined ? h("span", { className: r.confirmation_in_interval === false ? "bad" : "" }, fmt(r.confirmed)) : "–",
        r.standardised_residual !== undefined ? h("span", { className: Math.abs(r.standardised_residual) > 3 ? "bad" : "" }, fmt(r.standardised_residual, 3)) : "–",
        r.reachability !== undefined ? h("span", { className: r.reachable ? "good" : "bad" }, `${fmt(r.reachability, 3)} ${r.reachable ? "reachable" : "out of reach"}`) : "–",
        status(r.status)])),
    targetChart(rows),
    h("p", { className: "muted" }, "Grey: measured ± 1 u; blue: prediction and interval at the optimum; red: confirmation run; dashed: ±3 u."),
    h("h3", {}, "Optimum"), table(Object.keys(report.optimum || {}), [Object.values(report.optimum || {})]),
    report.meaning ? h("p", {}, report.meaning) : "",
    report.lack_of_fit ? h("p", {}, h("b", {}, "Lack of fit (model vs measurements): "),
      `chi2/dof ${fmt(report.lack_of_fit.chi2_per_dof, 3)} on ${report.lack_of_fit.dof} dof (noise band ${fmt(report.lack_of_fit.noise_band[0], 2)}–${fmt(report.lack_of_fit.noise_band[1], 2)}), p = ${fmt(report.lack_of_fit.p_value, 3)}`) : "",
    ...((report.conflicts?.active_bounds) || []).map((b) => h("p", { className: "bad" }, `${b.parameter} is pinned at its ${b.side} bound and pushes ${b.pushes}`)),
    ...((report.conflicts?.priors_pulled) || []).map((p) => h("p", { className: "bad" }, p.meaning)),
    report.surrogate_check ? h("p", {}, h("b", {}, "Response surfaces at the optimum: "), `${report.surrogate_check.verdict}: ${report.surrogate_check.reason}`) : "");
}

function modelsSection(models) {
  return h("section", { className: "card" }, h("h3", {}, "Fitted models"),
    Object.entries(models).map(([name, m]) => h("div", {}, h("h3", {}, name),
      m.ok ? [h("p", {}, h("code", {}, m.fit.equation_natural)),
        table(["Source", "Sum sq", "df", "Mean sq", "F", "p"], m.fit.anova.map((r) => [r.source, r.sum_of_squares, String(r.df), r.mean_square, r.f_value, r.p_value])),
        h("p", { className: "muted" }, `R² ${fmt(m.fit.fit_statistics.r_squared)}, adj. ${fmt(m.fit.fit_statistics.adj_r_squared)}; pure-error sd ${fmt(m.pure_error_sd)}`),
        m.fit.messages.map((msg) => h("p", { className: "muted" }, msg))]
        : h("p", { className: "bad" }, m.error))));
}

async function optional(path) {
  try { return await api(path); } catch (error) { if (error.status === 409 || error.status === 404) return null; throw error; }
}

export async function campaignPage(view, id) {
  const c = await api(`/campaigns/${id}`);
  const act = (action, call) => h("button", { className: "secondary", onclick: async () => {
    if (await attempt(call, `${action}: ok`)) campaignPage(view, id);
  } }, action);
  const cronInput = h("input", { value: "0 2 * * *", title: "5-field cron, UTC" });
  const schedule = h("p", {}, "Repeat on a schedule (cron, UTC) ", cronInput, " ",
    h("button", { className: "secondary", onclick: async () => {
      const body = { name: c.name, cron: cronInput.value, template: c.config, only_if_new_measurements: true };
      if (await attempt(() => api("/schedules", { method: "POST", body }), "schedule created")) location.hash = "#/schedules";
    } }, "Schedule (when new measurements arrive)"));
  const parts = [h("h2", {}, `Campaign #${c.id} ${c.name} `, status(c.status)),
    h("p", {}, c.status === "draft" ? act("start", () => api(`/campaigns/${id}/start`, { method: "POST" })) : "",
      c.status === "running" ? act("pause", () => api(`/campaigns/${id}/pause`, { method: "POST" })) : "",
      c.status === "paused" ? act("resume", () => api(`/campaigns/${id}/resume`, { method: "POST" })) : "",
      " ", h("a", { href: `#/jobs?campaign_id=${id}` }, "its jobs")),
    table(["Material", "Evaluator", "Fidelity", "Iteration", "Phase", "Runs done", "Failed"],
      [[h("a", { href: `#/materials/${c.material_id}` }, `#${c.material_id}`), c.evaluator, c.fidelity, String(c.current_iteration), c.phase || "–",
        `${c.runs_succeeded}/${c.runs_total}`, String(c.runs_failed)]])];
  if (c.error) parts.push(h("pre", { className: "bad" }, c.error));
  const [report, models, design] = await Promise.all([optional(`/campaigns/${id}/report`), optional(`/campaigns/${id}/models`), optional(`/campaigns/${id}/design`)]);
  if (report) parts.push(reportSection(report));
  if (models) parts.push(modelsSection(models.models));
  if (design) {
    const names = design.factors.map((f) => f.name);
    parts.push(h("section", { className: "card" }, h("h3", {}, `Design: ${design.kind}, ${design.resolution_label || ""}`),
      design.aliases && design.aliases.defining_relation.length ? h("p", {}, `Aliases: ${design.aliases.chains.filter((ch) => ch.aliases.length).map((ch) => ch.label).join("; ")}`) : "",
      table(["Std", "Run", "Type", "Seed", ...names, ...names.map((n) => `${n} (coded)`)],
        design.runs.map((r) => [String(r.std_order), String(r.run_order), r.point_type, String(r.seed), ...names.map((n) => r.natural[n]), ...names.map((n) => r.coded[n])]))));
  }
  parts.push(schedule);
  view.replaceChildren(...parts);
  return c.status === "running";
}

export async function schedulesPage(view) {
  const schedules = await api("/schedules");
  view.replaceChildren(h("h2", {}, "Schedules"),
    h("p", { className: "muted" }, "Missed runs coalesce: after downtime, at most one catch-up campaign starts. Create a schedule from a campaign's page."),
    table(["Id", "Name", "Cron (UTC)", "Enabled", "Only new data", "Next run", "Last campaign", ""],
      schedules.map((s) => [String(s.id), s.name, s.cron, s.enabled ? "yes" : "no", s.only_if_new_measurements ? "yes" : "no",
        s.next_run_at, s.last_campaign_id ? h("a", { href: `#/campaigns/${s.last_campaign_id}` }, `#${s.last_campaign_id}`) : "–",
        h("span", {},
          h("button", { className: "secondary", onclick: async () => {
            if (await attempt(() => api(`/schedules/${s.id}`, { method: "PATCH", body: { enabled: !s.enabled } }))) schedulesPage(view);
          } }, s.enabled ? "Disable" : "Enable"), " ",
          h("button", { className: "secondary", onclick: async () => {
            if (await attempt(() => api(`/schedules/${s.id}`, { method: "DELETE" }), "deleted")) schedulesPage(view);
          } }, "Delete"))])));
}
