// Inline SVG charts: line plots of result curves and a measured/predicted/confirmed comparison.
import { fmt } from "./core.js";

const NS = "http://www.w3.org/2000/svg";

function s(tag, attrs = {}, text) {
  const el = document.createElementNS(NS, tag);
  for (const [k, v] of Object.entries(attrs)) el.setAttribute(k, v);
  if (text !== undefined) el.textContent = text;
  return el;
}

function ticks(lo, hi, n = 5) {
  if (!(hi > lo)) return [lo];
  const raw = (hi - lo) / n, mag = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((m) => m * mag).find((v) => v >= raw);
  const out = [];
  for (let t = Math.ceil(lo / step) * step; t <= hi + step * 1e-9; t += step) out.push(t);
  return out;
}

function extent(values) {
  const finite = values.filter((v) => v !== null && Number.isFinite(v));
  if (!finite.length) return [0, 1];
  let lo = Math.min(...finite), hi = Math.max(...finite);
  if (lo === hi) { lo -= Math.abs(lo) * 0.05 || 1; hi += Math.abs(hi) * 0.05 || 1; }
  return [lo, hi];
}

// series: [{name, x: [...], y: [...]}]; columns in SI, labels say which.
export function lineChart(title, xLabel, yLabel, series, { width = 460, height = 280 } = {}) {
  const m = { l: 60, r: 12, t: 22, b: 38 };
  const svg = s("svg", { class: "chart", width, height, viewBox: `0 0 ${width} ${height}`, role: "img", "aria-label": title });
  const [x0, x1] = extent(series.flatMap((d) => d.x)), [y0, y1] = extent(series.flatMap((d) => d.y));
  const X = (v) => m.l + ((v - x0) / (x1 - x0)) * (width - m.l - m.r);
  const Y = (v) => height - m.b - ((v - y0) / (y1 - y0)) * (height - m.t - m.b);
  svg.append(s("text", { x: m.l, y: 14, class: "title" }, title));
  for (const t of ticks(x0, x1)) {
    svg.append(s("line", { x1: X(t), x2: X(t), y1: height - m.b, y2: height - m.b + 4, stroke: "#98a2b3" }));
    svg.append(s("text", { x: X(t), y: height - m.b + 14, "text-anchor": "middle" }, fmt(t, 3)));
  }
  for (const t of ticks(y0, y1)) {
    svg.append(s("line", { x1: m.l - 4, x2: width - m.r, y1: Y(t), y2: Y(t), stroke: "#eaecf0" }));
    svg.append(s("text", { x: m.l - 6, y: Y(t) + 3, "text-anchor": "end" }, fmt(t, 3)));
  }
  svg.append(s("text", { x: (m.l + width - m.r) / 2, y: height - 6, "text-anchor": "middle" }, xLabel));
  svg.append(s("text", { x: 12, y: (m.t + height - m.b) / 2, transform: `rotate(-90 12 ${(m.t + height - m.b) / 2})`, "text-anchor": "middle" }, yLabel));
  svg.append(s("rect", { x: m.l, y: m.t, width: width - m.l - m.r, height: height - m.t - m.b, fill: "none", stroke: "#98a2b3" }));
  const colours = ["#1f5fa8", "#d92d20", "#079455", "#dc6803", "#7a5af8"];
  series.forEach((d, i) => {
    const pts = d.x.map((x, j) => [x, d.y[j]]).filter(([x, y]) => Number.isFinite(x) && Number.isFinite(y));
    const path = pts.map(([x, y]) => `${X(x).toFixed(1)},${Y(y).toFixed(1)}`).join(" ");
    svg.append(s("polyline", { points: path, fill: "none", stroke: colours[i % colours.length], "stroke-width": 1.5 }));
    if (pts.length <= 12) for (const [x, y] of pts) svg.append(s("circle", { cx: X(x), cy: Y(y), r: 2.5, fill: colours[i % colours.length] }));
    if (series.length > 1) svg.append(s("text", { x: width - m.r - 4, y: m.t + 12 + 12 * i, "text-anchor": "end", fill: colours[i % colours.length] }, d.name));
  });
  return svg;
}

// One row per target, in units of the measurement's standard uncertainty around the measured mean:
// measured +-1u (grey band), predicted with its interval (blue), confirmed (red dot).
export function targetChart(rows, { width = 560 } = {}) {
  const usable = rows.filter((r) => r.status === "modelled" && r.measured_uncertainty > 0);
  const rowH = 28, m = { l: 210, r: 16, t: 26, b: 30 };
  const height = m.t + m.b + rowH * Math.max(usable.length, 1);
  const svg = s("svg", { class: "chart", width, height, viewBox: `0 0 ${width} ${height}`, role: "img", "aria-label": "targets" });
  svg.append(s("text", { x: 8, y: 16, class: "title" }, "Standardised: (value − measured) / u"));
  const z = (r, v) => (v - r.measured) / r.measured_uncertainty;
  const all = usable.flatMap((r) => [z(r, r.predicted), z(r, r.confirmed), ...(r.prediction_interval || []).filter((v) => v !== null).map((v) => z(r, v))]);
  const lim = Math.max(3.5, ...all.map(Math.abs).filter(Number.isFinite)) * 1.05;
  const X = (v) => m.l + ((v + lim) / (2 * lim)) * (width - m.l - m.r);
  for (const t of ticks(-lim, lim, 6)) {
    svg.append(s("line", { x1: X(t), x2: X(t), y1: m.t, y2: height - m.b, stroke: t === 0 ? "#667085" : "#eaecf0" }));
    svg.append(s("text", { x: X(t), y: height - m.b + 14, "text-anchor": "middle" }, fmt(t, 2)));
  }
  for (const edge of [-3, 3]) svg.append(s("line", { x1: X(edge), x2: X(edge), y1: m.t, y2: height - m.b, stroke: "#fda29b", "stroke-dasharray": "4 3" }));
  usable.forEach((r, i) => {
    const y = m.t + rowH * i + rowH / 2;
    svg.append(s("text", { x: 8, y: y + 3 }, `${r.test} ${r.quantity}`.slice(0, 34)));
    svg.append(s("rect", { x: X(-1), y: y - 8, width: X(1) - X(-1), height: 16, fill: "#eaecf0" }));
    const [lo, hi] = r.prediction_interval || [null, null];
    if (lo !== null && hi !== null) svg.append(s("line", { x1: X(z(r, lo)), x2: X(z(r, hi)), y1: y, y2: y, stroke: "#1f5fa8", "stroke-width": 2 }));
    svg.append(s("rect", { x: X(z(r, r.predicted)) - 3, y: y - 5, width: 6, height: 10, fill: "#1f5fa8" }));
    svg.append(s("circle", { cx: X(z(r, r.confirmed)), cy: y, r: 4, fill: "#d92d20" }));
  });
  return svg;
}
