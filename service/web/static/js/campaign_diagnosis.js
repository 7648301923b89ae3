// The diagnosis of one iteration: which candidate effect explains the misfit the fitted parameters
// cannot absorb. Ranking bars (score LM with its critical line, coloured by alias group), each
// effect's strength against its plausible range, the fingerprint table, alias groups with the
// measurement that separates them, and "add this effect and run the next iteration". Under "no
// physical match" and "suspect measurement" no effect is offered: only an override, styled apart,
// that asks for confirmation and tells the API so (override: true).
import { api, fmt, h, submitForm, table } from "./core.js";
import { humanText, quantityLabel } from "./labels.js";
import { numberInput, readNumber } from "./numbers.js";
import { COLOURS, axis, chart, textWidth } from "./plot.js";

const GROUP_COLOURS = ["#7a5af8", "#dc6803", "#0e9384", "#c11574"];
const colourOf = (r) => (r.alias_group ? GROUP_COLOURS[(r.alias_group - 1) % GROUP_COLOURS.length] : r.significant ? COLOURS[0] : "#98a2b3");

// The chart takes the card's width; its left margin is as wide as the longest effect name (measured,
// never truncated), the bars' "explained" labels have room on the right, and the critical value is
// written above the plot, where it cannot overlap the axis labels.
function rankingChart(d) {
  const rows = d.ranking;
  const names = rows.map((r) => `${r.title} (${r.effect})`);
  const explained = rows.map((r) => `${fmt(100 * r.explained, 2)} % explained`);
  return chart({ title: { text: "Effect ranking: score (LM) against its critical value" },
    grid: { left: textWidth(names, 10) + 16, right: textWidth(explained, 11) + 16, top: 52, bottom: 56 },
    yAxis: { type: "category", inverse: true, data: names, axisLabel: { fontSize: 10 } },
    xAxis: axis("Lagrange-multiplier score LM (-)", { min: 0, scale: false }),
    series: [{ type: "bar", name: "LM", barMaxWidth: 18,
      data: rows.map((r) => ({ value: r.lm, itemStyle: { color: colourOf(r) } })),
      label: { show: true, position: "right", formatter: (p) => explained[p.dataIndex] },
      markLine: { silent: true, symbol: "none", data: [{ xAxis: d.critical_lm }], lineStyle: { color: "#b42318", type: "dashed" },
        label: { formatter: `critical ${fmt(d.critical_lm, 3)}`, position: "start", color: "#b42318" } } }] },
  { height: 108 + 30 * rows.length, label: "effect ranking" });
}

// The strength the data ask for, on the plausible range's scale (0 = low end, 1 = high end).
function strengthBar(r) {
  const [lo, hi] = r.plausible_range || [null, null];
  if (!Number.isFinite(lo) || !Number.isFinite(hi) || !Number.isFinite(r.strength)) return fmt(r.strength);
  const frac = (r.strength - lo) / (hi - lo), pos = Math.max(0, Math.min(1, frac));
  return h("span", { className: "strength", title: `plausible ${fmt(lo)} – ${fmt(hi)} ${r.unit}` },
    h("span", { className: "range" }, h("span", { className: `mark ${frac < 0 || frac > 1 ? "outside" : ""}`, style: `left:${(100 * pos).toFixed(1)}%` })),
    ` ${fmt(r.strength, 3)} ${r.unit === "1" ? "" : r.unit} (${fmt(lo, 3)} – ${fmt(hi, 3)})`);
}

// What the strength column prints, as the CLI and the HTML report do (calibration.attribute.strength_reading):
// the estimate, a switch's share, or why there is none. An unseen candidate's estimate divides the misfit by a
// signature these measurements cannot see (a cohesion of -24,200 J/m2 was drawn); a negative one says the
// misfit points the other way from what the effect does.
function strengthCell(r, unseen) {
  const none = (why, title) => h("span", { className: "muted no-strength", title }, `none (${why})`);
  if (!r.significant && unseen.has(r.effect)) return none("unseen", "these measurements cannot see it, so they give no strength");
  const value = r.strength ?? r.fraction_of_switch;
  if (value === null || value === undefined) return "–";
  if (value < 0) return none("opposite sign", "the misfit points the other way from what the effect does");
  return r.strength === null || r.strength === undefined ? `${fmt(100 * value, 3)} % of the switch` : strengthBar(r);
}

// A bound as the input shows it: 1e8, not 100000000 (which the box cut to "1000000(").
// Three significant digits: a proposed range is twice an estimate (0.5393671226083385 overflowed the box).
const typed = (v) => {
  if (!Number.isFinite(v)) return v ?? "";
  const short = Number(v.toPrecision(3));
  return short !== 0 && (Math.abs(short) >= 1e5 || Math.abs(short) < 1e-3) ? short.toExponential().replace("e+", "e") : short;
};

function addEffectForm(campaignId, r, nextNumber, enabled, onAdded) {
  // the range the service proposes (from "off", so the next design keeps this model as its low face)
  const [lo, hi] = (r.proposed_range || r.plausible_range || [null, null]).map(typed);
  const form = h("form", { className: "add-effect", "data-effect": r.effect, novalidate: true },
    h("div", { className: "form-errors" }),
    h("label", {}, "strength low", numberInput({ name: "low", value: lo, "data-loc": "strength_range" })),
    h("label", {}, "high", numberInput({ name: "high", value: hi, "data-loc": "strength_range" })),
    h("button", { type: "submit", disabled: !enabled, title: enabled ? "" : "the campaign must be completed and this its latest iteration" },
      `Add ${r.title} and run iteration ${nextNumber}`));
  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const data = new FormData(form);
    const body = () => ({ add_effect: r.effect, strength_range: ["low", "high"].map((k) => readNumber(data.get(k), "strength_range")) });
    const done = await submitForm(form, () => api(`/campaigns/${campaignId}/iterations`, { method: "POST", body: body() }));
    if (done) onAdded(done);
  });
  return form;
}

// verdicts under which the diagnosis offers no effect (calibration.vocabulary.AGAINST_ADDING)
const AGAINST_ADDING = new Set(["no physical match", "suspect measurement"]);

// The override: one effect chosen from the ranking, added only after the user confirms that it goes
// against the diagnosis; never the primary button of the card.
function overrideForm(campaignId, d, nextNumber, enabled, onAdded) {
  const select = h("select", { name: "effect", "aria-label": "effect to add against the diagnosis" },
    d.ranking.map((r) => h("option", { value: r.effect }, `${r.title} (${r.effect}, explains ${fmt(100 * r.explained, 2)} %)`)));
  const form = h("form", { className: "override-effect", novalidate: true },
    h("div", { className: "form-errors" }), select,
    h("button", { type: "submit", className: "override", disabled: !enabled,
      title: enabled ? "against the diagnosis" : "the campaign must be completed and this its latest iteration" },
    `Override: add it anyway and run iteration ${nextNumber}`));
  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const effect = select.value;
    if (!window.confirm(`The diagnosis is "${d.verdict}": no candidate effect explains this misfit. Adding ${effect} goes against it and may only bend the parameters. Add it anyway?`)) return;
    const done = await submitForm(form, () => api(`/campaigns/${campaignId}/iterations`, { method: "POST", body: { add_effect: effect, override: true } }));
    if (done) onAdded(done);
  });
  return h("details", { className: "override" }, h("summary", {}, "Add an effect against the diagnosis…"),
    h("p", { className: "warning" }, `Against the diagnosis (${d.verdict}): ${humanText(d.message)}`), form);
}

// rows named by the effects' titles where the ranking has them (the table is read beside the chart)
function fingerprints(f, titles) {
  const cols = f.columns;
  const cell = (v) => h("span", { className: `fp fp-${v === "" ? "none" : v.includes("+") ? "up" : v.includes("-") ? "down" : "zero"}` }, v === "" ? "·" : v);
  return h("div", { className: "scroll fingerprints" }, table(["", ...cols.map((c) => quantityLabel(c))],
    [[h("b", {}, "observed"), ...cols.map((c) => cell(f.observed[c] ?? ""))],
      ...Object.entries(f.effects).map(([name, row]) => [titles[name] || name, ...cols.map((c) => cell(row[c] ?? ""))])]));
}

// the share of a signature the simulator's scatter accounts for: near 100 % the probe measured a packing's
// noise, not the effect, and its score is attenuated by about 1 - this (calibration.attribute.noise_share)
const probeNoise = (r) => (r.signature_noise ? h("span", { title: "share of the signature that is the simulator's scatter; the score is attenuated by about one minus this" },
  r.signature_noise >= 1 ? "mostly noise" : `${fmt(100 * r.signature_noise, 2)} %`) : "–");

// a candidate probed at its secant step and at its plausible top (calibration.attribute.top_probes): the share
// read (the better probe's) and each probe's, so a response that bends with strength shows
const explainedCell = (r) => ((r.probes || []).length > 1
  ? h("span", { className: "probes", title: "probed at the secant step and at the plausible top; the better probe is read, its p Bonferroni over both" },
    `${fmt(100 * r.explained, 3)} %`, h("br"),
    h("small", { className: "muted" }, r.probes.map((p) => `${fmt(100 * p.explained, 2)} % at ${fmt(p.strength_probed, 3)} ${r.unit}`).join(", ")))
  : `${fmt(100 * r.explained, 3)} %`);

// canAdd: the campaign is completed and this is its latest iteration.
export function diagnosisSection(campaignId, d, { canAdd, nextNumber, onAdded }) {
  const groups = d.alias_groups || [];
  const against = AGAINST_ADDING.has(d.verdict);
  const suggested = against ? [] : d.ranking.filter((r) => r.significant);
  // candidates these measurements could not see at any plausible strength (calibration/unseen.py)
  const unseen = new Map((d.unseen || []).map((u) => [u.effect, u]));
  // and those whose probes were too noisy to say whether they would be seen
  const undetermined = new Map((d.undetermined || []).map((u) => [u.effect, u]));
  // chart and fingerprints one under the other: side by side at 1280 px the chart truncated the
  // effects' names and the table hid its last columns (issue 31)
  return h("section", { className: "card diagnosis" }, h("h3", {}, `Diagnosis: ${d.verdict}`),
    h("p", {}, humanText(d.message)),
    rankingChart(d),
    h("h4", {}, "Fingerprints (sign of the change each effect makes)"), fingerprints(d.fingerprints, Object.fromEntries(d.ranking.map((r) => [r.effect, r.title]))),
    h("div", { className: "scroll" }, table(["Effect", "LM", "Holm p", "Explained", "Probe noise", "Strength (plausible range)", "Alias group", ""],
      d.ranking.map((r) => [
        h("span", {}, h("span", { className: "swatch", style: `background:${colourOf(r)}` }), ` ${r.title} `, h("code", {}, r.effect)),
        r.lm, r.p_holm, explainedCell(r), probeNoise(r), strengthCell(r, unseen), r.alias_group ? `group ${r.alias_group}` : "–",
        !r.significant && unseen.has(r.effect) ? h("span", { className: "muted unseen", title: `LM ${fmt(unseen.get(r.effect).lm_at_top, 2)} at its strongest plausible strength, ${fmt(unseen.get(r.effect).lm_needed, 3)} needed` }, "unseen by these measurements")
          : !r.significant && undetermined.has(r.effect) ? h("span", { className: "muted undetermined", title: `LM ${fmt(undetermined.get(r.effect).lm_at_top_low, 2)}-${fmt(undetermined.get(r.effect).lm_at_top_high, 2)} at its strongest plausible strength, ${fmt(undetermined.get(r.effect).lm_needed, 3)} needed` }, "not ruled out: probe too noisy")
          : !r.significant ? h("span", { className: "muted" }, "not significant")
          : against ? h("span", { className: "muted" }, "not offered: against the diagnosis")
            : addEffectForm(campaignId, r, nextNumber, canAdd, onAdded)]))),
    groups.length ? h("div", {}, h("h4", {}, "Alias groups: effects the data cannot tell apart"),
      h("ul", {}, groups.map((g) => h("li", {}, h("b", {}, `group ${g.group}: ${g.effects.join(", ")}. `), humanText(g.message || ""),
        h("ul", {}, (g.separators || []).map((s) => h("li", {}, `${s.effects.join(" vs ")}: measure ${humanText(s.separating_measurement)} (cos ${fmt(s.cos, 3)})`))))))) : "",
    (d.measure_next || []).length ? h("p", {}, h("b", {}, "Measure next: "), d.measure_next.map(humanText).join("; ")) : "",
    against ? overrideForm(campaignId, d, nextNumber, canAdd, onAdded)
      : suggested.length ? "" : h("p", { className: "muted" }, "No effect is significant: nothing to add."));
}
