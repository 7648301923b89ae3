// Across iterations: the weighted error (chi2 per degree of freedom) stacked by test, with the noise
// band and each step labelled with the effect added; and each parameter's optimum against its
// bounds and prior. From GET /campaigns/{id}/history and the iterations' configurations.
import { fmt, h, table } from "./core.js";
import { TEST_COLOURS, axis, band, chart, errorBars } from "./plot.js";

// the model's adequacy test: the omnibus lack of fit alone, or once the diagnosis ran, Holm over it and
// the candidates' directed test (calibration.stats.combined_p)
const adequacyCell = (it) => (it.directed_p === null || it.directed_p === undefined
  ? fmt(it.lack_of_fit_p, 2)
  : h("span", { title: "omnibus lack of fit · directed test → Holm over both" },
    `${fmt(it.lack_of_fit_p, 2)} · ${fmt(it.directed_p, 2)} → ${fmt(it.adequacy_p, 2)}`));

const stepLabel = (it) => `${it.number}${it.added_effect ? " + " + it.added_effect.join(", ") : ""}`;

function errorChart(iterations) {
  const tests = [...new Set(iterations.flatMap((it) => Object.keys(it.per_test || {})))];
  const labels = iterations.map(stepLabel);
  // the noise band of the last iteration (it narrows as dof grows; each is in the table)
  const last = iterations[iterations.length - 1];
  const series = tests.map((t, k) => ({
    type: "bar", stack: "chi2", name: t, barMaxWidth: 60, itemStyle: { color: TEST_COLOURS[t] },
    data: iterations.map((it) => (it.dof ? (it.per_test?.[t] ?? 0) / it.dof : null)),
    ...(k === tests.length - 1 ? {
      label: { show: true, position: "top", formatter: (p) => `χ²/dof ${fmt(iterations[p.dataIndex].chi2_per_dof, 3)}` },
      markArea: last?.noise_band ? band(Math.max(0, last.noise_band[0]), last.noise_band[1], "rgba(7,148,85,0.12)", "noise band") : undefined,
    } : {}),
  }));
  return chart({ title: { text: "Error history: χ²/dof per iteration, by test" }, legend: { top: 2, right: 6 },
    grid: { left: 56, right: 14, top: 40, bottom: 52 },
    xAxis: { type: "category", data: labels, name: "iteration (+ effect added)", nameLocation: "middle", nameGap: 30 },
    yAxis: axis("χ² / dof (-)", { min: 0, scale: false }), series }, { height: 300, label: "error history" });
}

// Each iteration's design bound as a segment of its own across its slot, broken between iterations
// ("-" is ECharts' empty value): a line through one point per iteration drew nothing for a factor that
// only one iteration has, typically the effect just added.
function box(rows, key) {
  return rows.flatMap((r) => [[r.number - 0.4, r[key] ?? "-"], [r.number + 0.4, r[key] ?? "-"], [r.number + 0.5, "-"]]);
}

function traceChart(name, rows) {
  // rows: [{number, value, interval, low, high, prior}]; interval: the report's 95 % one, cut at the box
  const series = [
    { type: "line", name: "optimum", data: rows.map((r) => [r.number, r.value]), symbolSize: 8, itemStyle: { color: "#1f5fa8" }, z: 3 },
    errorBars("95 % interval", rows.filter((r) => r.interval).map((r) => [r.number, r.value, null, null, r.interval[0], r.interval[1]]), "#1f5fa8"),
    { type: "line", name: "bounds", data: box(rows, "low"), showSymbol: false, lineStyle: { color: "#98a2b3", type: "dashed" } },
    { type: "line", name: "bounds ", data: box(rows, "high"), showSymbol: false, lineStyle: { color: "#98a2b3", type: "dashed" } },
  ];
  const prior = rows.find((r) => r.prior)?.prior;
  if (prior) series[0].markArea = band(prior.value - 2 * prior.uncertainty, prior.value + 2 * prior.uncertainty, "rgba(122,90,248,0.12)", "prior ±2u");
  const numbers = rows.map((r) => r.number);
  return chart({ title: { text: name, textStyle: { fontSize: 11 } }, grid: { left: 64, right: 10, top: 30, bottom: 36 },
    xAxis: axis("iteration", { min: Math.min(...numbers) - 0.5, max: Math.max(...numbers) + 0.5, scale: false,
      axisLabel: { customValues: numbers, formatter: (v) => String(v) }, axisTick: { customValues: numbers } }),
    yAxis: axis(""), series }, { height: 200, label: `trace ${name}` });
}

function parameterTraces(history, iterations, priors) {
  const names = [...new Set(history.iterations.flatMap((it) => Object.keys(it.optimum || {})))];
  const factorsOf = new Map(iterations.map((it) => [it.number, Object.fromEntries((it.parameters?.factors || []).map((f) => [f.name, f]))]));
  return names.map((name) => traceChart(name, history.iterations.filter((it) => it.optimum && name in it.optimum).map((it) => {
    const f = factorsOf.get(it.number)?.[name];
    return { number: it.number, value: it.optimum[name], interval: it.parameter_interval?.[name], low: f?.low, high: f?.high,
      prior: priors.find((p) => p.parameter === name) };
  })));
}

// What an iteration ran (calibration.history.batteries): its total, the reused design rows, and why
// each phase ran as many as it did in the cell's tooltip.
function batteriesCell(b) {
  if (!b) return "–";
  const phases = `design ${b.design}, confirmation ${b.confirmation}, polish ${b.polish}, diagnosis ${b.diagnosis}`;
  return h("span", { className: "batteries", title: [phases, ...(b.why || [])].join("\n") },
    `${b.total}${b.reused ? ` (+${b.reused} reused)` : ""}`);
}

// Whether the effect an iteration added was kept against its base (calibration.decisions) and, where the loop
// ended fitting an alias in its place, which iteration's model it keeps (calibration.automatic.settle_alias).
function automaticCell(it) {
  const parts = [];
  // an alias fitted for comparison earned its place against the base, but another iteration's model is kept
  const compared = it.kept_iteration != null && it.kept_iteration !== it.number;
  if (it.decision) parts.push(h("span", { className: it.decision.accepted ? "good" : "bad" },
    `${it.decision.effect} ${it.decision.accepted ? (compared ? "beats the base" : "kept") : "rejected"}`));
  if (it.kept_iteration != null) parts.push(h("span", { className: it.undistinguished ? "kept-iteration bad" : "kept-iteration", title: it.stop_reason || "" },
    ` · model kept: iteration ${it.kept_iteration}` + (it.undistinguished ? ` (undistinguished: ${it.undistinguished.join(" / ")})` : "")));
  // a completed loop taken up again from here (POST .../continue): what it had stopped for
  if (it.continued) parts.push(h("span", { className: "continued", title: it.continued.stopped_for || "" },
    `${parts.length ? " · " : ""}continued (limit ${it.continued.max_iterations}; had stopped: ${it.continued.stopped_for || "–"})`));
  return parts.length ? h("span", {}, ...parts) : "–";
}

export function historySection(history, iterations, priors) {
  const its = history.iterations;
  if (!its.length) return "";
  // the table takes the card's width (eight columns do not fit beside the chart); the chart sits under it
  return h("section", { className: "card history" }, h("h3", {}, "Across iterations"),
    h("div", {}, h("div", { className: "scroll" }, table(["Iteration", "Effects", "χ²/dof", "Noise band", "p (omnibus · directed → Holm)", "Verdict", "Next", "Automatic", "Added effect", "Batteries"],
        its.map((it) => [String(it.number), (it.effects.length ? it.effects.join(", ") : "none") + (it.range_widened ? " (range widened)" : "") + (it.box_widened?.length ? ` (box widened: ${it.box_widened.join(", ")})` : ""),
          h("span", { className: "chi2dof", "data-iteration": String(it.number) }, fmt(it.chi2_per_dof, 4)),
          it.noise_band ? `${fmt(Math.max(0, it.noise_band[0]), 2)} – ${fmt(it.noise_band[1], 2)}` : "–",
          adequacyCell(it), it.verdict || "–",
          // automatic mode between candidates of one score: the cheaper went first, and the cell says so
          it.effect_added_next ? (it.tie_break ? h("span", { className: "tie-break", title: it.tie_break },
            `+ ${it.effect_added_next.join(", ")} (tie: fewest spheres)`) : `+ ${it.effect_added_next.join(", ")}`) : "–",
          // automatic mode: whether the effect this iteration added was kept (calibration.decisions)
          automaticCell(it),
          // an added effect explains the misfit only when every check holds; otherwise what it leaves
          it.explains ? h("span", { className: `explains ${it.explains.explains === "explains" ? "good" : "bad"}`, title: it.explains.explains_message }, it.explains.explains) : "–",
          batteriesCell(it.batteries)]))),
      h("div", { className: "panels" }, errorChart(its))),
    h("h4", {}, "Parameters: optimum with its 95 % interval (the report's, cut at the design box) against the box (dashed) and priors"),
    h("div", { className: "panels small" }, parameterTraces(history, iterations, priors)));
}
