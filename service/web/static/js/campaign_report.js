// One iteration's report: the verdict (printed once), the targets as a parity plot per test, the
// standardised residual strip with its +-2 band, reachability against its cutoff, and the table.
import { fmt, h, status, wideTable } from "./core.js";
import { conditionText, humanText, quantityLabel, targetLabel } from "./labels.js";
import { COLOURS, TEST_COLOURS, axis, band, chart, errorBars, roundRange } from "./plot.js";

const modelled = (report) => report.targets.filter((r) => r.status === "modelled" && Number.isFinite(r.measured));
// sigma of a residual: the measurement's and the simulator's standard uncertainties together (the
// report's residual_sd divides the simulator's by the number of confirmation seeds)
const sigma = (r) => r.residual_sd ?? Math.hypot(r.measured_uncertainty || 0, r.simulator_sd || 0);

export function verdictSection(report) {
  const lof = report.lack_of_fit;
  const failing = (report.tests || []).filter((t) => t.fails).map((t) => t.test);
  return h("section", { className: "card verdict" },
    h("h3", {}, "Verdict: ", h("span", { className: `status verdict-${(report.verdict || "").replaceAll(" ", "_")}` }, report.verdict)),
    report.meaning ? h("p", {}, humanText(report.meaning)) : "",
    // what holds and what does not: "calibrated" only when every check holds (calibration.verdict.checks)
    (report.checks || []).length ? h("ul", { className: "checks" }, report.checks.map((c) => h("li", {
      className: c.holds === false ? "bad" : c.holds === true ? "good" : "muted", "data-mark": c.holds === false ? "✗" : c.holds === true ? "✓" : "–",
      "data-check": c.check }, h("b", {}, `${c.check}: `), humanText(c.detail)))) : "",
    ...((report.suspect_measurements) || []).map((s) => h("p", { className: "bad suspect-measurement" }, h("b", {}, "Suspect measurement: "), humanText(s.message))),
    lof ? h("p", {}, h("b", {}, "Model against measurements: "),
      `χ²/dof ${fmt(lof.chi2_per_dof, 3)} on ${lof.dof} dof (noise band ${fmt(lof.noise_band[0], 2)} – ${fmt(lof.noise_band[1], 2)}), p = ${fmt(lof.p_value, 3)}`,
      failing.length ? h("span", { className: "bad" }, ` · failing tests: ${failing.join(", ")}`) : "") : "",
    report.adequacy ? h("p", {}, h("b", {}, "With the candidate effects' directed test: "),
      `p = ${fmt(report.adequacy.directed?.p_value, 3)}; together with the lack of fit (Holm) p = ${fmt(report.adequacy.p_value, 3)}: `,
      h("span", { className: report.adequacy.fails ? "bad" : "" }, report.adequacy.fails ? "the model misses the measurements" : "no misfit beyond noise")) : "",
    ...((report.conflicts?.active_bounds) || []).map((b) => h("p", { className: "bad" }, `${b.parameter} is pinned at its ${b.side} bound: ${humanText(b.meaning)}`)),
    ...((report.conflicts?.priors_pulled) || []).map((p) => h("p", { className: "bad" }, humanText(p.meaning))),
    // measurements stored despite a likely unit slip: repeated wherever they are used
    ...(report.warnings || []).map((w) => h("p", { className: "warning" }, w)),
    report.surrogate_check ? h("p", { className: "muted" }, h("b", {}, "Response surfaces at the optimum: "), `${report.surrogate_check.verdict}: ${humanText(report.surrogate_check.reason)}`) : "",
    report.polish ? polishLines(report.polish) : "");
}

// How the optimum was polished on the batteries, and why; each anchor (a point of a missed measured
// parameter's profile, run beside the Jacobian: calibration.analysis.anchored_points) on a line of its own.
function polishLines(polish) {
  if (polish.skipped) {
    return h("p", { className: "muted polish" }, h("b", {}, "Polishing on the batteries: "),
      `skipped, the surfaces predicted the confirmation (${humanText(polish.skipped)})`);
  }
  const held = (a) => Object.entries(a.held).map(([k, v]) => `${k} ${fmt(v, 3)}`).join(", ");
  return h("div", { className: "polish" },
    h("p", { className: "muted" }, h("b", {}, "Polishing on the batteries: "),
      `${polish.steps} Gauss-Newton step(s), ${polish.batteries} batteries, χ² ${fmt(polish.chi2_start, 3)} → ${fmt(polish.chi2, 3)}, `
      + `Jacobian from the ${polish.jacobian || "batteries"}` + (polish.why ? `; why: ${humanText(polish.why)}` : "")),
    (polish.anchors || []).length ? h("ul", { className: "anchors muted" }, polish.anchors.map((a) => h("li", {
      className: a.taken ? "taken" : "" }, `held at the measured ${held(a)}: `
      + (a.chi2 === null || a.chi2 === undefined ? "its batteries have not run yet" : `χ² ${fmt(a.chi2, 3)}, `)
      + (a.chi2 === null || a.chi2 === undefined ? "" : a.taken ? "the batteries preferred it: the steps started here" : "not better than the optimum")
      + (a.step_chi2 === null || a.step_chi2 === undefined ? "" : `; one step from it: χ² ${fmt(a.step_chi2, 3)}, `
        + (a.step_taken ? "the best trial: the polish went on from there" : "not taken"))))) : "",
    // after a step, the chosen point at fresh seeds: the verdict above reads these batteries (calibration.polish.hold_out)
    (polish.holdout_seeds || []).length ? h("p", { className: "muted holdout" }, h("b", {}, "Held out: "),
      `the chosen point again at ${polish.holdout_seeds.length} fresh seed(s), χ² ${fmt(polish.holdout_chi2, 3)}; `
      + "the report reads these batteries, on which no step was chosen") : "");
}

// Parity per test. Quantities of one test have different units, so each is divided by its own
// mean measured value (over its conditions): the diagonal is "model = measurement" for all of them,
// and the bars are +-2 sigma on the same scale.
function parityPanel(test, rows) {
  const byQuantity = new Map();
  for (const r of rows) { if (!byQuantity.has(r.quantity)) byQuantity.set(r.quantity, []); byQuantity.get(r.quantity).push(r); }
  const series = [];
  let lo = Infinity, hi = -Infinity;
  [...byQuantity.entries()].forEach(([quantity, group], k) => {
    const ref = group.reduce((s, r) => s + Math.abs(r.measured), 0) / group.length || 1;
    const colour = COLOURS[k % COLOURS.length];
    const points = group.map((r) => {
      const model = Number.isFinite(r.confirmed) ? r.confirmed : r.predicted;
      const x = r.measured / ref, y = model / ref, ux = (2 * (r.measured_uncertainty || 0)) / ref, uy = (2 * sigma(r)) / ref;
      lo = Math.min(lo, x - ux, y - uy); hi = Math.max(hi, x + ux, y + uy);
      return { value: [x, y, x - ux, x + ux, y - uy, y + uy], name: targetLabel(r) };
    });
    series.push({ type: "scatter", name: quantityLabel(quantity), data: points, symbolSize: 9, itemStyle: { color: colour }, z: 3,
      tooltip: { formatter: (p) => `${p.name}<br>measured/ref ${fmt(p.value[0], 3)}, model/ref ${fmt(p.value[1], 3)}` } });
    series.push(errorBars(`${quantityLabel(quantity)} ±2σ`, points.map((p) => p.value), colour));
  });
  const pad = (hi - lo) * 0.04 || 0.05;
  const range = roundRange(lo - pad, hi + pad);  // both axes the same round range: the diagonal is at 45°
  const [a, b] = [range.min, range.max];
  series.push({ type: "line", name: "model = measured", data: [[a, a], [b, b]], showSymbol: false, silent: true,
    lineStyle: { color: "#98a2b3", type: "dashed", width: 1 }, z: 0 });
  return chart({ title: { text: `Parity: ${test}` }, legend: { top: 20, left: 4, type: "scroll", textStyle: { fontSize: 10 }, data: [...byQuantity.keys()].map(quantityLabel) },
    grid: { left: 56, right: 14, top: 60, bottom: 44 },
    xAxis: axis("measured / mean measured (-)", range), yAxis: axis("model / mean measured (-)", range), series },
  { height: 300, label: `parity ${test}` });
}

function residualStrip(rows) {
  const labels = rows.map(targetLabel);
  const data = rows.map((r, i) => ({ value: [i, r.standardised_residual], name: labels[i], itemStyle: { color: TEST_COLOURS[r.test] || COLOURS[0] } }));
  const predicted = rows.map((r, i) => ({ value: [i, r.predicted_standardised_residual], name: labels[i] }));
  const extreme = Math.max(3, ...rows.flatMap((r) => [Math.abs(r.standardised_residual || 0), Math.abs(r.predicted_standardised_residual || 0)])) * 1.05;
  const range = roundRange(-extreme, extreme);  // symmetric about 0, ending on round ticks
  return chart({ title: { text: "Standardised residuals (model − measured) / σ" },
    legend: { top: 2, right: 6, data: ["confirmation", "surface prediction"] },
    grid: { left: 56, right: 14, top: 36, bottom: 110 },
    xAxis: { type: "category", data: labels, axisLabel: { rotate: 35, fontSize: 10, interval: 0 } },
    yAxis: axis("residual (σ)", range),
    series: [
      { type: "scatter", name: "confirmation", data, symbolSize: 10, z: 3, markArea: band(-2, 2, "rgba(7,148,85,0.10)", "±2σ"),
        markLine: { silent: true, symbol: "none", data: [{ yAxis: 0 }], lineStyle: { color: "#667085" }, label: { show: false } } },
      { type: "scatter", name: "surface prediction", data: predicted, symbol: "emptyCircle", symbolSize: 8, itemStyle: { color: "#667085" } },
    ] }, { height: 320, label: "residual strip" });
}

function reachabilityBars(rows, cutoff) {
  const labels = rows.map(targetLabel);
  return chart({ title: { text: "Reachability: closest the design box gets (min |z|)" },
    grid: { left: 210, right: 30, top: 34, bottom: 40 },
    yAxis: { type: "category", data: labels, inverse: true, axisLabel: { fontSize: 10, width: 200, overflow: "truncate" } },
    xAxis: axis("min |standardised residual| over the box (σ)", { min: 0, scale: false }),
    series: [{ type: "bar", name: "reachability", barMaxWidth: 16,
      data: rows.map((r) => ({ value: r.reachability, itemStyle: { color: r.reachable ? "#079455" : "#d92d20" } })),
      markLine: { silent: true, symbol: "none", data: [{ xAxis: cutoff, name: "cutoff" }], lineStyle: { color: "#b42318", type: "dashed" },
        label: { formatter: `cutoff ${cutoff}`, position: "end" } } }] },
  { height: 60 + 26 * rows.length, label: "reachability" });
}

// The calibrated parameters with their 95 % intervals (calibration.intervals): what the measurements fix and
// what they do not (pairs that trade), and where points measured on the batteries widened an interval beyond
// the response surfaces' view (intervals.measured_points), with the interval it replaced.
export function parametersSection(report) {
  const iv = report.intervals;
  if (!iv || !iv.parameters) return "";
  const widened = new Set(iv.measured_points?.widened || []);
  const notes = (name, p) => [
    p.at_bound ? `cut at the box (${p.at_bound.join(", ")})` : "",
    widened.has(name) && p.wald ? `widened to the points measured on the batteries (the surfaces' alone: ${fmt(p.wald.low)} – ${fmt(p.wald.high)})` : "",
  ].filter(Boolean).join("; ") || "–";
  return h("section", { className: "card parameters" }, h("h3", {}, `Parameters: optimum and ${fmt(100 * iv.level, 3)} % interval`),
    wideTable(["Parameter", "Optimum", "sd", "Interval", "Note"], Object.entries(iv.parameters).map(([name, p]) => [
      name, fmt(p.value), p.sd === null || p.sd === undefined ? "not identified" : fmt(p.sd, 3),
      h("span", { className: "interval", "data-parameter": name }, p.low === null || p.low === undefined ? "–" : `${fmt(p.low)} – ${fmt(p.high)}`),
      notes(name, p)])),
    iv.scaled_by_misfit ? h("p", { className: "muted" }, `Intervals widened by χ²/dof ${fmt(iv.scale, 3)}: the model misses the measurements by more than their noise.`) : "",
    ...(iv.trades || []).map((t) => h("p", { className: "bad trade" }, humanText(t.message))),
    (iv.unidentified || []).length ? h("p", { className: "bad" }, `Not identified by these measurements: ${iv.unidentified.join(", ")}`) : "",
    iv.about ? h("p", { className: "muted" }, `How: ${iv.about}.`) : "");
}

// what the "confirmed" values are: one battery, or the mean of several seeds' batteries
function seedsText(report) {
  const m = report.confirmation_seeds?.length || 1;
  return m > 1 ? `mean of the ${m} confirmation runs (one per seed)` : "confirmation run";
}

export function targetsSection(report) {
  const rows = modelled(report);
  const tests = [...new Set(rows.map((r) => r.test))];
  const cutoff = report.reachable_limit ?? 3;
  return h("section", { className: "card" }, h("h3", {}, "Targets"),
    h("div", { className: "panels" }, tests.map((t) => parityPanel(t, rows.filter((r) => r.test === t)))),
    h("p", { className: "muted" }, `Dots: ${seedsText(report)} at the optimum (the surface's prediction where it has none); horizontal bars ±2 u of the measurement, vertical ±2σ of the residual (the simulator's scatter divided by the number of seeds).`),
    rows.length ? residualStrip(rows) : "",
    rows.some((r) => Number.isFinite(r.reachability)) ? reachabilityBars(rows.filter((r) => Number.isFinite(r.reachability)), cutoff) : "",
    wideTable(["Test", "Quantity", "Condition", "Measured ± u", "Predicted [95% PI]", "Confirmed", "z", "Reachability", "Status"],
      report.targets.map((r) => {
        const fails = Number.isFinite(r.standardised_residual) && Math.abs(r.standardised_residual) > 2;
        return [r.test, quantityLabel(r.quantity), conditionText(r.condition) || "–",
          r.measured_uncertainty ? `${fmt(r.measured)} ± ${fmt(r.measured_uncertainty, 3)} ${r.unit || ""}${r.uncertainty_assumed ? " (assumed)" : ""}` : fmt(r.measured),
          r.predicted !== undefined ? `${fmt(r.predicted)} [${fmt(r.prediction_interval?.[0])}, ${fmt(r.prediction_interval?.[1])}]` : "–",
          r.confirmed !== undefined && r.confirmed !== null ? h("span", { className: r.confirmation_in_interval === false ? "bad" : "" }, fmt(r.confirmed)) : "–",
          r.standardised_residual !== undefined ? h("span", { className: fails ? "bad target-fails" : "target-ok" }, fmt(r.standardised_residual, 3)) : "–",
          r.reachability !== undefined ? h("span", { className: r.reachable ? "good" : "bad" }, `${fmt(r.reachability, 3)} ${r.reachable ? "reachable" : "out of reach"}`) : "–",
          // why a target is not modelled, or that its surface rests on fewer runs or on ln(y)
          r.note ? h("span", {}, status(r.status), h("div", { className: "muted target-note" }, r.note)) : status(r.status)];
      })));
}
