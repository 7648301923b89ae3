// A campaign's page, the calibration loop's cockpit: drive it (start, pause, resume), pick an
// iteration, read its verdict, targets, conditions and diagnosis, add the indicated effect to run
// the next iteration, and follow the error and the parameters across iterations.
import { API, api, attempt, duration, fmt, h, optional, status, table } from "./core.js";
import { humanText } from "./labels.js";
import { refresh } from "./live.js";
import { parametersSection, targetsSection, verdictSection } from "./campaign_report.js";
import { conditionsSection } from "./campaign_conditions.js";
import { diagnosisSection } from "./campaign_diagnosis.js";
import { historySection } from "./campaign_history.js";
import { designSection, modelsSection } from "./campaign_models.js";

// Iterations shown as tabs: the service's largest page of iterations (a campaign rarely has more than
// the automatic mode's 10; a later one asked for by number is read on its own).
const ITERATION_TABS = 100;

function goTo(hash) {
  if (location.hash === hash) refresh(); else location.hash = hash;
}

function controls(c, id) {
  const act = (label, call) => h("button", { className: "secondary", "data-action": label, onclick: async () => {
    if (await attempt(call, `${label}: ok`)) refresh();
  } }, label);
  return h("p", { className: "controls" },
    c.status === "draft" ? act("Start", () => api(`/campaigns/${id}/start`, { method: "POST" })) : "",
    c.status === "running" ? act("Pause", () => api(`/campaigns/${id}/pause`, { method: "POST" })) : "",
    c.status === "paused" ? act("Resume", () => api(`/campaigns/${id}/resume`, { method: "POST" })) : "",
    // a failed battery failed the campaign: queue it again and run on, the batteries that succeeded kept
    c.status === "failed" ? act("Retry", () => api(`/campaigns/${id}/retry`, { method: "POST" })) : "",
    " ", h("a", { href: `#/jobs?campaign_id=${id}` }, "its jobs"), " · ", h("a", { href: `#/materials/${c.material_id}` }, "its material"));
}

// The calibrated iteration travels as files: the shareable report (one self-contained HTML file) and the
// neutral material card (docs/export.md); plain links, as reads need no token.
function exportLinks(id, n) {
  const file = (path, name, text, title) => h("a", { href: `${API}/campaigns/${id}/${path}`, download: name, title,
    className: "button secondary", "data-export": path.split("?")[0] }, text);
  return h("p", { className: "exports" }, h("b", {}, `Iteration ${n} as a file: `),
    file(`report.html?number=${n}&download=true`, `campaign-${id}-report.html`, "Report (HTML)",
      "verdict, targets, diagnosis and history in one self-contained HTML file that reads offline"), " ",
    file(`material-card?number=${n}&format=yaml`, `campaign-${id}.card.yaml`, "Material card (YAML)",
      "the calibrated material: particles, contact law and effects in SI with units, rig and provenance"));
}

function progressCard(c) {
  const pct = c.runs_total ? Math.round((100 * (c.runs_succeeded + c.runs_failed)) / c.runs_total) : 0;
  return h("section", { className: "card progress" },
    h("p", {}, h("b", {}, `Iteration ${c.current_iteration}: `), `phase ${c.phase || "starting"}, runs ${c.runs_succeeded}/${c.runs_total} done`,
      c.runs_failed ? h("span", { className: "bad" }, `, ${c.runs_failed} failed`) : "", " ",
      h("span", { className: "bar" }, h("span", { style: `width:${pct}%` }))),
    h("p", { className: "muted" }, "This page updates by itself while the campaign runs."));
}

function iterationTabs(id, iterations, selected) {
  if (!iterations.length) return "";
  return h("nav", { className: "iterations", "aria-label": "iterations" }, h("span", { className: "muted" }, "Iteration: "),
    iterations.map((it) => {
      const effects = it.effects;
      return h("a", { href: `#/campaigns/${id}?iteration=${it.number}`, className: it.number === selected ? "selected" : "",
        "aria-current": it.number === selected ? "page" : undefined, title: `phase ${it.phase}` },
      `${it.number}${effects.length ? " · " + effects.join(", ") : ""}${it.report ? "" : " (running)"}`);
    }));
}

function scheduleForm(c) {
  const cronInput = h("input", { value: "0 2 * * *", title: "5-field cron, UTC", "aria-label": "cron" });
  return h("p", { className: "muted" }, "Repeat on a schedule (cron, UTC) ", cronInput, " ",
    h("button", { className: "secondary", onclick: async () => {
      const body = { name: c.name, cron: cronInput.value, template: c.config, only_if_new_measurements: true };
      if (await attempt(() => api("/schedules", { method: "POST", body }), "schedule created")) location.hash = "#/schedules";
    } }, "Schedule (when new measurements arrive)"));
}

export async function campaignPage(view, id, params) {
  const [c, iterationPage, history] = await Promise.all([api(`/campaigns/${id}`), api(`/campaigns/${id}/iterations?limit=${ITERATION_TABS}`), api(`/campaigns/${id}/history`)]);
  const iterations = iterationPage.items;
  const asked = Number(params?.get("iteration"));
  if (asked && !iterations.some((x) => x.number === asked)) {  // beyond the tabs' page: read that one
    const one = await optional(`/campaigns/${id}/iterations/${asked}`);
    if (one) iterations.push(one);
  }
  const it = iterations.find((x) => x.number === asked) || iterations.find((x) => x.number === c.current_iteration) || iterations[iterations.length - 1];
  const latest = iterations.length ? Math.max(...iterations.map((x) => x.number)) : 0;
  const parts = [h("h2", {}, `Campaign #${c.id} ${c.name} `, status(c.status)), controls(c, id),
    table(["Material", "Evaluator", "Fidelity", "Iteration", "Phase", "Runs done", "Failed"],
      [[h("a", { href: `#/materials/${c.material_id}` }, `#${c.material_id}`), c.evaluator, c.fidelity, String(c.current_iteration), c.phase || "–",
        `${c.runs_succeeded}/${c.runs_total}`, String(c.runs_failed)]]),
    iterationTabs(id, iterations, it?.number)];
  // the rig and resolution's warnings (a coarse factor capped, a box small for its particles, targets left
  // out because they cannot be compared there) and the plausibility warnings of the settings
  const e = c.estimate;  // the cost model's ceilings where the batteries run (engine.lab.cost.estimate_view)
  if (e) parts.push(h("p", { className: "campaign-estimate" }, h("b", {}, "Each battery: "),
    `about ${e.particles.toLocaleString("en")} particles, up to ${Math.round(e.simulated_time_s)} s simulated, in rig ${e.rig} `
    + `at resolution ${e.resolution} (sizes x ${Number(e.scale_factor.toPrecision(3))}); ${e.batteries} batteries in the first design`
    + (e.wall_time_s == null ? "." : `; about ${duration(e.wall_time_s)} per battery here (${duration(e.wall_time_range_s[0])}`
       + `-${duration(e.wall_time_range_s[1])}; ${e.wall_time_basis}).`)));
  if (c.warnings?.length) parts.push(h("ul", { className: "campaign-warnings" }, c.warnings.map((w) => h("li", {}, humanText(w)))));
  if (c.error) parts.push(h("p", { className: "job-error" }, h("b", {}, "Failed: "), humanText(c.error)));
  if (c.stop_reason) parts.push(h("p", { className: "stop-reason" }, h("b", {}, "Automatic mode stopped: "), humanText(c.stop_reason),
    // stopped where more iterations could go on (the limit, an alias left unfitted): take it up again
    c.continuable ? [" ", h("button", { className: "secondary", "data-action": "continue", onclick: async () => {
      if (await attempt(() => api(`/campaigns/${id}/continue`, { method: "POST", body: { more_iterations: 1 } }),
        "continuing with one more iteration")) goTo(`#/campaigns/${id}`);
    } }, "Continue with one more iteration")] : ""));
  // an alias fitted in place of an effect that passed: the model kept may be an earlier iteration's
  if (c.kept_iteration != null && c.kept_iteration !== c.current_iteration) parts.push(h("p", { className: "kept-iteration" },
    h("b", {}, "Model kept: "), `iteration ${c.kept_iteration}'s (see the history); iteration ${c.current_iteration} fitted its alias for comparison.`));
  if (c.status === "running" || c.status === "paused") parts.push(progressCard(c));
  if (it) {
    const effects = it.effects;
    parts.push(h("p", { className: "active-effects" }, h("b", {}, `Iteration ${it.number} model: `),
      effects.length ? `contact effects ${effects.join(", ")}` : "no contact effects beyond the base contact law",
      `; factors ${(it.parameters?.factors || []).map((f) => f.name).join(", ")}.`));
  }
  if (it?.report) {
    const n = it.number;
    const [report, models] = await Promise.all([api(`/campaigns/${id}/report?number=${n}`), optional(`/campaigns/${id}/models?number=${n}`)]);
    const confirmation = report.confirmation_job_id ? await optional(`/jobs/${report.confirmation_job_id}/result`) : null;
    parts.push(verdictSection(report), exportLinks(id, n), parametersSection(report), targetsSection(report), conditionsSection(report.targets, confirmation));
    if (report.diagnosis) {
      parts.push(diagnosisSection(id, report.diagnosis, {
        canAdd: c.status === "completed" && n === latest, nextNumber: latest + 1,
        onAdded: () => goTo(`#/campaigns/${id}`),
      }));
    }
    parts.push(historySection(history, iterations, c.config?.priors || []));
    if (models) parts.push(modelsSection(models.models));
  } else if (history.iterations.length) {
    parts.push(historySection(history, iterations, c.config?.priors || []));
  }
  if (it?.design) parts.push(designSection(it.design));
  parts.push(scheduleForm(c));
  view.replaceChildren(...parts);
  return c.status === "running";
}
