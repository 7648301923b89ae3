// Jobs: the submission form (fields from the OpenAPI schema), the list with progress, and a result page.
import { api, attempt, condition, flash, h, status, table } from "./core.js";
import { lineChart } from "./charts.js";

let schemaCache = null;
async function schemas() {
  if (!schemaCache) schemaCache = (await api("/openapi.json")).components.schemas;
  return schemaCache;
}

function numberField(name, prop) {
  const value = prop.default ?? "";
  return h("label", { title: prop.description || "" }, name, h("input", { name, type: "number", step: "any", value }));
}

export async function submitPage(view) {
  const defs = await schemas();
  const micro = defs.MicroParameters.properties;
  const form = h("form", { className: "card" },
    h("h2", {}, "Submit a job"),
    h("div", {},
      h("label", {}, "Test", h("select", { name: "test" }, ["battery", "fill", "cct", "dst", "aor", "anchor"].map((t) => h("option", {}, t)))),
      h("label", {}, "Fidelity", h("select", { name: "fidelity" }, h("option", {}, "screening"), h("option", {}, "thesis"))),
      h("label", {}, "Evaluator", h("select", { name: "evaluator" }, h("option", {}, "dem"), h("option", {}, "analytic"))),
      h("label", {}, "Seed", h("input", { name: "seed", type: "number", min: 0, value: 0 })),
      h("label", {}, "Priority", h("input", { name: "priority", type: "number", value: 0 }))),
    h("h3", {}, "Micro parameters (SI)"),
    h("div", {}, Object.entries(micro).filter(([, p]) => p.type === "number" || (p.anyOf || []).some((a) => a.type === "number"))
      .map(([name, prop]) => numberField(name, prop))),
    h("h3", {}, "Options"),
    h("div", {},
      h("label", {}, "DST normal stresses (kPa, comma-separated)", h("input", { name: "dst_kpa", placeholder: "fidelity default" })),
      h("label", {}, "Include angle of repose", h("input", { name: "include_aor", type: "checkbox" })),
      h("label", {}, "Include anchor pull-out", h("input", { name: "include_anchor", type: "checkbox" }))),
    h("button", { type: "submit" }, "Queue job"));
  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const data = new FormData(form);
    const parameters = {};
    for (const name of Object.keys(micro)) {
      const raw = data.get(name);
      if (raw !== null && raw !== "") parameters[name] = Number(raw);
    }
    const options = { include_aor: data.get("include_aor") === "on", include_anchor: data.get("include_anchor") === "on" };
    const dst = String(data.get("dst_kpa") || "").trim();
    if (dst) options.dst_normal_stresses_pa = dst.split(",").map((v) => Number(v) * 1000);
    const body = { test: data.get("test"), fidelity: data.get("fidelity"), evaluator: data.get("evaluator"),
      seed: Number(data.get("seed")), priority: Number(data.get("priority")), parameters, options };
    const job = await attempt(() => api("/jobs", { method: "POST", body }));
    if (job) location.hash = `#/jobs/${job.id}`;
  });
  view.replaceChildren(form);
}

function progress(job) {
  const pct = Math.round(100 * (job.progress?.fraction || 0));
  return h("span", {}, h("span", { className: "bar", title: `${pct}%` }, h("span", { style: `width:${pct}%` })),
    ` ${pct}% ${job.progress?.phase || ""}`);
}

export async function jobsPage(view, params) {
  const filter = params.get("status") || "";
  const query = new URLSearchParams({ limit: "100" });
  if (filter) query.set("status", filter);
  if (params.get("campaign_id")) query.set("campaign_id", params.get("campaign_id"));
  const list = await api(`/jobs?${query}`);
  const select = h("select", { onchange: (e) => { location.hash = `#/jobs${e.target.value ? "?status=" + e.target.value : ""}`; } },
    ["", "queued", "running", "succeeded", "failed", "cancelled"].map((s) => h("option", { value: s, selected: s === filter }, s || "all")));
  view.replaceChildren(h("h2", {}, `Jobs (${list.total})`), h("p", {}, "Status ", select, " ", h("a", { href: "#/submit" }, "submit a job")),
    table(["Id", "Test", "Evaluator", "Fidelity", "Seed", "Status", "Progress", "Campaign", "Created"],
      list.items.map((j) => [h("a", { href: `#/jobs/${j.id}` }, `#${j.id}`), j.test, j.evaluator, j.fidelity, String(j.seed),
        status(j.status), progress(j), j.campaign_id ? h("a", { href: `#/campaigns/${j.campaign_id}` }, `#${j.campaign_id}`) : "–",
        j.created_at.replace("T", " ").slice(0, 19)])));
  return list.items.some((j) => j.status === "queued" || j.status === "running");  // keep refreshing
}

function curveCharts(curves) {
  return Object.entries(curves || {}).map(([name, columns]) => {
    const keys = Object.keys(columns);
    if (keys.length < 2) return null;
    const [xKey, ...yKeys] = keys;
    return lineChart(name, xKey, yKeys.length === 1 ? yKeys[0] : "", yKeys.map((k) => ({ name: k, x: columns[xKey], y: columns[k] })));
  }).filter(Boolean);
}

export async function jobPage(view, id) {
  const job = await api(`/jobs/${id}`);
  const actions = h("p", {},
    h("button", { className: "secondary", disabled: !["queued", "running"].includes(job.status),
      onclick: async () => { if (await attempt(() => api(`/jobs/${id}/cancel`, { method: "POST" }), "cancel requested")) jobPage(view, id); } }, "Cancel"), " ",
    h("button", { className: "secondary", disabled: !["failed", "cancelled"].includes(job.status),
      onclick: async () => { if (await attempt(() => api(`/jobs/${id}/retry`, { method: "POST" }), "queued again")) jobPage(view, id); } }, "Retry"));
  const parts = [h("h2", {}, `Job #${job.id} `, status(job.status)), actions,
    table(["Test", "Evaluator", "Fidelity", "Seed", "Attempts", "Progress", "Engine", "Wall time (s)"],
      [[job.test, job.evaluator, job.fidelity, String(job.seed), `${job.attempts}/${job.max_attempts}`, progress(job),
        job.engine_version || "–", job.wall_time_s]])];
  if (job.error) parts.push(h("h3", {}, "Error"), h("pre", {}, job.error));
  if (job.result_available) {
    const result = await api(`/jobs/${id}/result`);
    parts.push(h("h3", {}, "Bulk properties"),
      table(["Test", "Quantity", "Condition", "Value", "Unit"],
        result.properties.map((p) => [p.test, p.quantity, condition(p.condition), p.value, p.unit])),
      h("h3", {}, "Curves"), h("div", {}, curveCharts(result.curves)),
      h("h3", {}, "Provenance"), h("pre", {}, JSON.stringify(result.provenance, null, 1)));
  }
  parts.push(h("h3", {}, "Spec"), h("pre", {}, JSON.stringify(job.spec, null, 1)));
  view.replaceChildren(...parts);
  flash("");
  return job.status === "queued" || job.status === "running";
}

