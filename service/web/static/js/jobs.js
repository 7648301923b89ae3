// Jobs: the submission form (micro parameters from the OpenAPI schema, effects from the catalogue),
// the list with progress, and a job's page (status, one-line error, properties, engineering curves).
import { api, attempt, condition, h, oneLine, pageQuery, pager, schemas, status, submitForm, table } from "./core.js";
import { catalogue, effectPicker, pickedEffects } from "./effects.js";
import { evaluatorSelect, evaluators } from "./evaluators.js";
import { curveViews } from "./jobcurves.js";
import { batteryChecks, batteryOptions, labTests, testSelect } from "./labtests.js";
import { refresh } from "./live.js";
import { numberInput, numberListField, readNumber, readNumberList } from "./numbers.js";

function numberField(name, prop, loc) {
  const value = prop.default ?? "";
  return h("label", { title: prop.description || "" }, name,
    numberInput({ name, value, "data-loc": loc }));
}

const isNumber = (p) => p.type === "number" || p.type === "integer" || (p.anyOf || []).some((a) => a.type === "number" || a.type === "integer");

export async function submitPage(view) {
  const [defs, effects, backends, tests] = await Promise.all([schemas(), catalogue(), evaluators(), labTests()]);
  const micro = defs.MicroParameters.properties;
  const numeric = Object.entries(micro).filter(([, p]) => isNumber(p));
  const form = h("form", { className: "card", id: "submit-job", novalidate: true },
    h("h2", {}, "Submit a job"),
    h("div", { className: "form-errors" }),
    h("div", {},
      h("label", {}, "Test", testSelect(tests, "test")),
      h("label", {}, "Fidelity", h("select", { name: "fidelity", "data-loc": "fidelity" }, h("option", {}, "screening"), h("option", {}, "thesis"))),
      h("label", {}, "Evaluator", evaluatorSelect(backends, defs.JobSubmit)),
      h("label", {}, "Seed", h("input", { name: "seed", type: "number", value: 0, "data-loc": "seed" })),
      h("label", {}, "Priority", h("input", { name: "priority", type: "number", value: 0, "data-loc": "priority" }))),
    h("h3", {}, "Micro parameters (SI)"),
    h("div", {}, numeric.map(([name, prop]) => numberField(name, prop, `parameters.${name}`))),
    effectPicker(effects.effects, "parameters.effects"),
    h("h3", {}, "Options"),
    h("div", {},
      numberListField("DST normal stresses (kPa)", "dst_kpa", "options.dst_normal_stresses_pa", "fidelity default"),
      batteryChecks(tests, (option) => `options.${option}`)),
    h("p", {}, h("button", { type: "submit" }, "Queue job")));
  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const data = new FormData(form);
    const options = batteryOptions(tests, data);
    const body = () => {  // inside the submission, so that a number typed wrongly is shown beside its field
      const parameters = {};
      for (const [name] of numeric) {
        const value = readNumber(data.get(name), `parameters.${name}`);
        if (value !== null) parameters[name] = value;
      }
      const effectsPicked = pickedEffects(form);
      if (Object.keys(effectsPicked).length) parameters.effects = effectsPicked;
      const dst = readNumberList(data.get("dst_kpa"), "options.dst_normal_stresses_pa");
      if (dst.length) options.dst_normal_stresses_pa = dst.map((kpa) => kpa * 1000);
      return { test: data.get("test"), fidelity: data.get("fidelity"), evaluator: data.get("evaluator"),
        seed: Number(data.get("seed")), priority: Number(data.get("priority")), parameters, options };
    };
    const job = await submitForm(form, () => api("/jobs", { method: "POST", body: body() }));
    if (job) location.hash = `#/jobs/${job.id}`;
  });
  view.replaceChildren(form);
  return false;
}

function progress(job) {
  const pct = Math.round(100 * (job.progress?.fraction || 0));
  return h("span", {}, h("span", { className: "bar", title: `${pct}%` }, h("span", { style: `width:${pct}%` })),
    ` ${pct}% ${job.progress?.phase || ""}`);
}

// Which jobs the list shows by where they came from (GET /jobs?origin=): the jobs submitted here by
// default, since campaigns queue their batteries by the hundred; a campaign's "its jobs" link
// (campaign_id) shows that campaign's.
const ORIGINS = [["direct", "submitted directly"], ["campaign", "campaign batteries"], ["all", "all"]];

const JOBS_PAGE = 100;

export async function jobsPage(view, params) {
  const filter = params.get("status") || "";
  const campaign = params.get("campaign_id") || "";
  const origin = params.get("origin") || (campaign ? "all" : "direct");
  const query = pageQuery(params, { origin, status: filter, campaign_id: campaign }, JOBS_PAGE);
  const [list, defs] = await Promise.all([api(`/jobs?${query}`), schemas()]);
  // the page's own address keeps the filters, so a refresh or a shared link shows the same list
  const go = (changed) => {
    const next = new URLSearchParams({ ...Object.fromEntries(params), offset: "", ...changed });  // a new filter starts at its first page
    for (const [key, value] of [...next]) if (!value) next.delete(key);
    location.hash = `#/jobs${next.size ? "?" + next : ""}`;
  };
  const select = h("select", { name: "status", onchange: (e) => go({ status: e.target.value }) },
    ["", ...defs.JobStatus.enum].map((s) => h("option", { value: s, selected: s === filter }, s || "all")));
  const originSelect = h("select", { name: "origin", onchange: (e) => go({ origin: e.target.value }) },
    ORIGINS.map(([value, text]) => h("option", { value, selected: value === origin }, text)));
  view.replaceChildren(h("h2", {}, `Jobs (${list.total})`),
    h("p", { className: "filters" }, h("label", {}, "Status ", select), " ", h("label", {}, "Origin ", originSelect), " ",
      campaign ? [h("span", { className: "muted" }, `campaign #${campaign} `), h("a", { href: "#/jobs?origin=all" }, "every job"), " · "] : "",
      h("a", { href: "#/submit" }, "submit a job")),
    h("div", { className: "scroll" }, table(["Id", "Test", "Evaluator", "Fidelity", "Seed", "Status", "Progress", "Campaign", "Created"],
      list.items.map((j) => [h("a", { href: `#/jobs/${j.id}` }, `#${j.id}`), j.test, j.evaluator, j.fidelity, String(j.seed),
        status(j.status), progress(j), j.campaign_id ? h("a", { href: `#/campaigns/${j.campaign_id}` }, `#${j.campaign_id}`) : "–",
        j.created_at.replace("T", " ").slice(0, 19)]))), pager(list, params, "/jobs"));
  return list.items.some((j) => j.status === "queued" || j.status === "running");  // keep refreshing
}

export async function jobPage(view, id) {
  const job = await api(`/jobs/${id}`);
  const actions = h("p", {},
    h("button", { className: "secondary", disabled: !["queued", "running"].includes(job.status),
      onclick: async () => { if (await attempt(() => api(`/jobs/${id}/cancel`, { method: "POST" }), "cancel requested")) refresh(); } }, "Cancel"), " ",
    h("button", { className: "secondary", disabled: !["failed", "cancelled"].includes(job.status),
      onclick: async () => { if (await attempt(() => api(`/jobs/${id}/retry`, { method: "POST" }), "queued again")) refresh(); } }, "Retry"));
  const parts = [h("h2", {}, `Job #${job.id} `, status(job.status)), actions,
    h("div", { className: "scroll" }, table(["Test", "Evaluator", "Fidelity", "Seed", "Attempts", "Progress", "Engine", "Wall time (s)", "Campaign"],
      [[job.test, job.evaluator, job.fidelity, String(job.seed), `${job.attempts}/${job.max_attempts}`, progress(job),
        job.engine_version || "–", job.wall_time_s, job.campaign_id ? h("a", { href: `#/campaigns/${job.campaign_id}` }, `#${job.campaign_id}`) : "–"]]))];
  if (job.error) parts.push(h("p", { className: "job-error" }, h("b", {}, job.status === "failed" ? "Failed: " : "Error: "), oneLine(job.error)));
  if (job.result_available) {
    const result = await api(`/jobs/${id}/result`);
    parts.push(h("h3", {}, "Curves"), h("div", { className: "charts" }, curveViews(result.curves || {}, result.properties)),
      h("h3", {}, "Bulk properties"),
      table(["Test", "Quantity", "Condition", "Value", "Unit"],
        result.properties.map((p) => [p.test, p.quantity, condition(p.condition), p.value, p.unit])),
      h("details", {}, h("summary", {}, "Provenance"), h("pre", {}, JSON.stringify(result.provenance, null, 1))));
  }
  parts.push(h("details", {}, h("summary", {}, "Spec"), h("pre", {}, JSON.stringify(job.spec, null, 1))));
  view.replaceChildren(...parts);
  return job.status === "queued" || job.status === "running";
}
