// Condition panels: how the model and the measurements change with the normal stress, where either
// has data at several stresses. The model side is the first confirmation run's own result (one
// battery at the optimum: shear stress, dilatancy and E' per load, with its Mohr-Coulomb line, which
// the report's per-target mean does not have); the measured side is the targets.
//   shear stress against normal stress, with the measured and the modelled Mohr-Coulomb lines;
//   log E' (and the unload-reload E_ur where measured) against log normal stress; dilatancy angle
//   against normal stress.
import { fmt, h } from "./core.js";
import { axis, band, chart } from "./plot.js";

const KPA = 1e-3, MPA = 1e-6, RAD = Math.PI / 180;
const sigmaOf = (row) => row.condition?.normal_stress_pa;
const perLoad = (rows, test, quantity) => rows.filter((r) => r.test === test && r.quantity === quantity && Number.isFinite(sigmaOf(r)))
  .sort((a, b) => sigmaOf(a) - sigmaOf(b));
const overall = (rows, test, quantity) => rows.find((r) => r.test === test && r.quantity === quantity && !Object.keys(r.condition || {}).length);

function mcLine(name, phiDeg, cPa, sMaxPa, style) {
  const c = (cPa || 0) * KPA, tan = Math.tan(phiDeg * RAD), s = sMaxPa * KPA * 1.1;
  return { type: "line", name, data: [[0, c], [s, c + tan * s]], showSymbol: false, lineStyle: style, silent: true };
}

function shearPanel(targets, props) {
  const model = perLoad(props, "dst", "residual_shear_stress_pa");
  const measured = perLoad(targets, "dst", "residual_shear_stress_pa");
  if (!model.length && !measured.length) return null;
  const sMax = Math.max(...[...model, ...measured].map(sigmaOf));
  const series = [];
  if (measured.length) series.push({ type: "scatter", name: "measured", data: measured.map((r) => [sigmaOf(r) * KPA, r.measured * KPA]), symbol: "diamond", symbolSize: 10, itemStyle: { color: "#101828" } });
  if (model.length) series.push({ type: "scatter", name: "model", data: model.map((p) => [sigmaOf(p) * KPA, p.value * KPA]), symbolSize: 9, itemStyle: { color: "#1f5fa8" } });
  const phiM = overall(targets, "dst", "friction_angle_deg"), cM = overall(targets, "dst", "cohesion_pa");
  if (phiM) series.push(mcLine(`measured: φ ${fmt(phiM.measured, 3)}°, c ${cM ? fmt(cM.measured * KPA, 3) + " kPa" : "0 (not measured)"}`, phiM.measured, cM?.measured, sMax, { color: "#101828", type: "dashed" }));
  const phiP = overall(props, "dst", "friction_angle_deg"), cP = overall(props, "dst", "cohesion_pa");
  if (phiP) series.push(mcLine(`model: φ ${fmt(phiP.value, 3)}°, c ${fmt((cP?.value || 0) * KPA, 3)} kPa`, phiP.value, cP?.value, sMax, { color: "#1f5fa8" }));
  return chart({ title: { text: "Shear strength: τ against σn" }, legend: { top: 20, left: 4, textStyle: { fontSize: 10 } },
    grid: { left: 60, right: 14, top: 62, bottom: 44 }, xAxis: axis("normal stress σn (kPa)", { min: 0 }), yAxis: axis("residual shear stress τ (kPa)", { min: 0 }), series },
  { height: 300, label: "shear against normal stress" });
}

// E' and, where measured, the unload-reload modulus E_ur: on log-log axes a power law E ~ σ^n is a line,
// and a model whose E_ur rises less steeply than the measured one misses the contact law (Hertz, n + 1/3)
function modulusPanel(targets, props) {
  const kinds = [["confined_modulus_pa", "E'", "circle"], ["unload_reload_modulus_pa", "E_ur", "triangle"]];
  const series = [], shown = [];
  for (const [quantity, label, symbol] of kinds) {
    const model = perLoad(props, "cct", quantity);
    const measured = perLoad(targets, "cct", quantity);
    if (model.length < 2 && measured.length < 2) continue;
    shown.push(label);
    if (measured.length) series.push({ type: "line", name: `${label} measured`, data: measured.map((r) => [sigmaOf(r) * KPA, r.measured * MPA]), symbol: "diamond", symbolSize: 10, itemStyle: { color: "#101828" }, lineStyle: { type: "dashed" } });
    if (model.length) series.push({ type: "line", name: `${label} model`, data: model.map((p) => [sigmaOf(p) * KPA, p.value * MPA]), symbol, symbolSize: 8, itemStyle: { color: label === "E'" ? "#1f5fa8" : "#dc6803" } });
  }
  if (!shown.length) return null;
  const onlyLoading = shown.length === 1 && shown[0] === "E'";
  return chart({ title: { text: `Stiffness: ${shown.join(" and ")} against σn (log-log)` },
    legend: { top: 20, left: 4 }, grid: { left: 60, right: 14, top: 56, bottom: 44 },
    xAxis: axis("normal stress σn (kPa)", { type: "log" }), yAxis: axis(onlyLoading ? "confined modulus E' (MPa)" : "modulus (MPa)", { type: "log" }), series },
  { height: 300, label: "modulus against stress" });
}

function dilatancyPanel(targets, props) {
  const model = perLoad(props, "dst", "dilatancy_angle_deg");
  const measured = perLoad(targets, "dst", "dilatancy_angle_deg");
  if (!model.length && !measured.length) return null;
  const series = [];
  if (measured.length) series.push({ type: "scatter", name: "measured", data: measured.map((r) => [sigmaOf(r) * KPA, r.measured]), symbol: "diamond", symbolSize: 10, itemStyle: { color: "#101828" } });
  if (model.length) series.push({ type: "line", name: "model", data: model.map((p) => [sigmaOf(p) * KPA, p.value]), symbolSize: 8, itemStyle: { color: "#1f5fa8" } });
  const all = overall(targets, "dst", "dilatancy_angle_deg");
  if (all && !measured.length && series.length) {
    const u = 2 * (all.measured_uncertainty || 0);
    series[0].markLine = { silent: true, symbol: "none", data: [{ yAxis: all.measured, name: "measured (mean over loads)" }], lineStyle: { color: "#101828", type: "dashed" }, label: { formatter: `measured ${fmt(all.measured, 3)}°`, position: "insideEndTop" } };
    if (u > 0) series[0].markArea = band(all.measured - u, all.measured + u, "rgba(16,24,40,0.07)", "±2u");
  }
  return chart({ title: { text: "Dilatancy angle against σn" }, legend: { top: 20, left: 4 }, grid: { left: 60, right: 14, top: 56, bottom: 44 },
    xAxis: axis("normal stress σn (kPa)", { min: 0 }), yAxis: axis("dilatancy angle ψ (deg)"), series },
  { height: 300, label: "dilatancy against stress" });
}

// targets: the report's rows; result: the confirmation job's result (null when not available).
export function conditionsSection(targets, result) {
  const props = result?.properties || [];
  const panels = [shearPanel(targets, props), modulusPanel(targets, props), dilatancyPanel(targets, props)].filter(Boolean);
  if (!panels.length) return "";
  return h("section", { className: "card" }, h("h3", {}, "Across conditions (the first confirmation run at the optimum)"),
    h("div", { className: "panels" }, panels));
}
