// A job's curves as engineers read them: one quantity per axis, units on the axes.
// CCT: stress-strain loops per cycle, E' per cycle and per stress window, the unload-reload
// modulus against stress; DST: shear stress and lid rise against shear displacement per load, and
// the Mohr-Coulomb envelope; fill settling; the angle-of-repose profile per sector. Curves this
// module does not know are drawn one column per chart against the first column, so nothing stored
// is hidden.
import { fmt, h } from "./core.js";
import { axis, chart } from "./plot.js";

const KPA = 1e-3, MM = 1e3, MPA = 1e-6;
const scale = (values, k) => values.map((v) => (v === null || v === undefined ? null : v * k));
const pairs = (xs, ys) => xs.map((x, i) => [x, ys[i]]).filter(([x, y]) => Number.isFinite(x) && Number.isFinite(y));
const line = (name, data, extra = {}) => ({ type: "line", name, data, showSymbol: data.length <= 12, symbolSize: 5, lineStyle: { width: 1.4 }, ...extra });
const legend = { top: 20, left: 56, right: 6, type: "scroll", textStyle: { fontSize: 10 } };
const grid = { left: 64, right: 16, top: 52, bottom: 44 };

function xy(title, xName, yName, series, { logY = false, height } = {}) {
  return chart({ title: { text: title }, legend: series.length > 1 ? legend : undefined, grid,
    tooltip: { trigger: "axis" }, xAxis: axis(xName), yAxis: axis(yName, logY ? { type: "log" } : {}), series }, { height });
}

function cctLoops(c) {
  const byCycle = new Map();
  c.cycle.forEach((k, i) => {
    if (!byCycle.has(k)) byCycle.set(k, []);
    byCycle.get(k).push([c.normal_strain[i], c.normal_stress_pa[i] * KPA]);
  });
  const series = [...byCycle.entries()].sort((a, b) => a[0] - b[0])
    .map(([k, data]) => line(k > 0 ? `cycle ${k}` : "pre-load", data.filter(([x, y]) => Number.isFinite(x) && Number.isFinite(y)), { showSymbol: false }));
  return xy("CCT: stress-strain loops", "normal strain (-)", "normal stress (kPa)", series);
}

function mohrCoulomb(points, properties) {
  const phi = properties.find((p) => p.test === "dst" && p.quantity === "friction_angle_deg" && !Object.keys(p.condition || {}).length);
  const c = properties.find((p) => p.test === "dst" && p.quantity === "cohesion_pa" && !Object.keys(p.condition || {}).length);
  const series = [{ type: "scatter", name: "residual (per load)", data: points, symbolSize: 8 }];
  if (phi) {
    const sMax = Math.max(...points.map(([s]) => s)) * 1.1;
    const c0 = (c ? c.value : 0) * KPA, tan = Math.tan((phi.value * Math.PI) / 180);
    series.push(line(`envelope: φ = ${fmt(phi.value, 3)}°, c = ${fmt(c0, 3)} kPa`, [[0, c0], [sMax, c0 + tan * sMax]], { showSymbol: false, lineStyle: { type: "dashed" } }));
  }
  return chart({ title: { text: "DST: Mohr-Coulomb envelope" }, legend, grid, xAxis: axis("normal stress (kPa)", { min: 0 }),
    yAxis: axis("shear stress (kPa)", { min: 0 }), series });
}

export function curveViews(curves, properties = []) {
  const out = [];
  const done = new Set();
  const take = (name) => { done.add(name); return curves[name]; };
  if (curves.fill_settling) {
    const c = take("fill_settling");
    const positive = c.kinetic_energy_ratio.every((v) => v > 0);
    out.push(xy("Fill: settling", "time (s)", "kinetic energy ratio (-)", [line("kinetic energy ratio", pairs(c.time_s, c.kinetic_energy_ratio), { showSymbol: false })], { logY: positive }));
  }
  if (curves.cct) out.push(cctLoops(take("cct")));
  if (curves.cct_modulus_per_cycle) {
    const c = take("cct_modulus_per_cycle");
    out.push(chart({ title: { text: "CCT: confined modulus E' per cycle" }, grid,
      xAxis: axis("cycle", { type: "category", data: c.cycle.map(String) }), yAxis: axis("E' (MPa)"),
      series: [{ type: "bar", name: "E'", data: scale(c.confined_modulus_pa, MPA), barMaxWidth: 36 }] }));
  }
  if (curves.cct_modulus_vs_stress) {
    const c = take("cct_modulus_vs_stress");
    out.push(xy("CCT: E' per stress window", "normal stress (kPa)", "E' (MPa)", [line("E'", pairs(scale(c.normal_stress_pa, KPA), scale(c.confined_modulus_pa, MPA)), { showSymbol: true })]));
  }
  if (curves.cct_unload_reload_modulus_vs_stress) {
    // log-log, so a power law E ~ sigma^n is a straight line whose slope reads the contact law
    // (n ~ 1/3 more for Hertz than linear springs); the loading E' beside it for the ratio E_ur / E'
    const ur = take("cct_unload_reload_modulus_vs_stress");
    const series = [line("E_ur (unload-reload)", pairs(scale(ur.normal_stress_pa, KPA), scale(ur.unload_reload_modulus_pa, MPA)), { showSymbol: true })];
    const win = curves.cct_modulus_vs_stress;
    if (win) series.push(line("E' (loading, per window)", pairs(scale(win.normal_stress_pa, KPA), scale(win.confined_modulus_pa, MPA)), { showSymbol: true, lineStyle: { width: 1.4, type: "dashed" } }));
    out.push(chart({ title: { text: "CCT: unload-reload modulus against stress" }, legend, grid, tooltip: { trigger: "axis" },
      xAxis: axis("normal stress (kPa)", { type: "log" }), yAxis: axis("modulus (MPa)", { type: "log" }), series }));
  }
  const dst = Object.keys(curves).filter((k) => /^dst_\d+$/.test(k)).sort((a, b) => Number(a.slice(4)) - Number(b.slice(4)));
  if (dst.length) {
    const label = (k) => `σn ${fmt(Number(k.slice(4)) * KPA, 3)} kPa`;
    out.push(xy("DST: shear stress", "shear displacement (mm)", "shear stress (kPa)",
      dst.map((k) => line(label(k), pairs(scale(curves[k].shear_displacement_m, MM), scale(curves[k].shear_stress_smoothed_pa || curves[k].shear_stress_pa, KPA)), { showSymbol: false }))));
    out.push(xy("DST: lid rise (dilation)", "shear displacement (mm)", "lid rise (mm)",
      dst.map((k) => line(label(k), pairs(scale(curves[k].shear_displacement_m, MM), scale(curves[k].lid_rise_m, MM)), { showSymbol: false }))));
    dst.forEach((k) => done.add(k));
  }
  if (curves.dst_envelope || curves.mohr_coulomb) {
    const env = curves.dst_envelope ? take("dst_envelope") : take("mohr_coulomb");
    const sigma = env.residual_normal_stress_pa || env.normal_stress_pa;
    out.push(mohrCoulomb(pairs(scale(sigma, KPA), scale(env.residual_shear_stress_pa, KPA)), properties));
  }
  const profiles = Object.keys(curves).filter((k) => /^aor_profile_\d+$/.test(k));
  if (profiles.length) {
    out.push(xy("Angle of repose: heap profile per sector", "radius (mm)", "surface height (mm)",
      profiles.map((k) => line(`sector ${k.slice(12)}`, pairs(scale(curves[k].radius_m, MM), scale(curves[k].surface_height_m, MM)), { showSymbol: false }))));
    profiles.forEach((k) => done.add(k));
  }
  if (curves.aor_lift) {
    const c = take("aor_lift");
    out.push(xy("Angle of repose: bucket lift", "time (s)", "bucket rise (mm)", [line("bucket rise", pairs(c.time_s, scale(c.bucket_rise_m, MM)), { showSymbol: false })]));
  }
  if (curves.anchor) {
    const c = take("anchor");
    out.push(xy("Anchor: pull-out", "displacement (mm)", "pull force (N)", [line("pull force", pairs(scale(c.displacement_m, MM), c.pull_force_n), { showSymbol: false })]));
  }
  for (const [name, columns] of Object.entries(curves)) {
    if (done.has(name)) continue;
    const [xKey, ...yKeys] = Object.keys(columns);
    for (const yKey of yKeys) out.push(xy(`${name}: ${yKey}`, xKey, yKey, [line(yKey, pairs(columns[xKey], columns[yKey]))]));
  }
  return out.length ? out : [h("p", { className: "muted" }, "This job stored no curves.")];
}
