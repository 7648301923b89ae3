// Charts: Apache ECharts (vendored, see ../vendor/README.md) with the SVG renderer, so the text of a
// chart (titles, axis names with units, labels) is in the page like any other text.
// chart(option) returns a box; the chart is drawn once the box is in the page (it needs a size).
import * as echarts from "../vendor/echarts-6.1.0/echarts.esm.min.js";
import { fmt, h } from "./core.js";

export const COLOURS = ["#1f5fa8", "#d92d20", "#079455", "#dc6803", "#7a5af8", "#0e9384", "#c11574", "#667085"];
export const TEST_COLOURS = { fill: "#1f5fa8", cct: "#dc6803", dst: "#079455", aor: "#7a5af8", anchor: "#c11574" };
const instances = new Set();

const BASE = {
  animation: false,
  color: COLOURS,
  textStyle: { fontFamily: "system-ui, -apple-system, 'Segoe UI', sans-serif", fontSize: 11 },
  title: { left: 4, top: 2, textStyle: { fontSize: 12, fontWeight: 600 } },
  tooltip: { trigger: "item", confine: true, valueFormatter: (v) => fmt(v) },
};

// One axis: its name carries the unit; numbers in engineering-friendly form.
export function axis(name, extra = {}) {
  return { type: "value", name, nameLocation: "middle", nameGap: extra.type === "category" ? 28 : 42, scale: true,
    axisLabel: { formatter: (v) => fmt(v, 3), hideOverlap: true }, splitLine: { lineStyle: { color: "#eaecf0" } }, ...extra };
}

// The width in pixels of the widest of these texts in the charts' font: a margin that fits the
// labels exactly instead of truncating them ("rolling resistance (rolling_eps...").
let measurer = null;
export function textWidth(texts, fontSize = 11) {
  measurer = measurer || document.createElement("canvas").getContext("2d");
  measurer.font = `${fontSize}px ${BASE.textStyle.fontFamily}`;
  return Math.ceil(Math.max(0, ...texts.map((t) => measurer.measureText(String(t)).width)));
}

// An axis range that starts and ends on round ticks: [lo, hi] widened to multiples of a 1-2-5
// step giving about `ticks` intervals. Ends at arbitrary values (0.862 beside the tick 0.87)
// printed labels that overlapped their neighbours. Returns { min, max, interval } for axis().
export function roundRange(lo, hi, ticks = 5) {
  if (!Number.isFinite(lo) || !Number.isFinite(hi)) return {};
  if (hi <= lo) { const pad = Math.abs(lo) * 0.05 || 0.05; lo -= pad; hi += pad; }
  const raw = (hi - lo) / ticks, power = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * power).find((st) => st >= raw);
  // rounded through toPrecision, so that 0.1 * 9 is the tick 0.9, not 0.9000000000000001
  const snap = (v) => Number(v.toPrecision(12));
  return { min: snap(Math.floor(lo / step) * step), max: snap(Math.ceil(hi / step) * step), interval: snap(step) };
}

export function chart(option, { height = 280, label = "" } = {}) {
  const box = h("div", { className: "chart", style: `height:${height}px`, role: "img", "aria-label": label || option.title?.text || "chart" });
  requestAnimationFrame(() => {
    if (!box.isConnected) return;
    const instance = echarts.init(box, null, { renderer: "svg" });
    instance.setOption({ ...BASE, ...option, title: { ...BASE.title, ...(option.title || {}) },
      tooltip: { ...BASE.tooltip, ...(option.tooltip || {}) } });
    instances.add(instance);
  });
  return box;
}

// Free the charts of views that were replaced (the pages re-render every refresh).
export function sweepCharts() {
  for (const instance of instances) {
    if (!instance.getDom().isConnected) { instance.dispose(); instances.delete(instance); }
  }
}

window.addEventListener("resize", () => { for (const instance of instances) instance.resize(); });

// Error bars as an ECharts custom series. rows: [x, y, xLow, xHigh, yLow, yHigh] (null where a
// direction has no bar); both directions widen the axes so that no bar is cut.
export function errorBars(name, rows, colour) {
  return {
    type: "custom", name, data: rows, silent: true, z: 1, encode: { x: [0, 2, 3], y: [1, 4, 5] },
    renderItem(params, api) {
      const children = [];
      const style = { stroke: colour, lineWidth: 1.2 };
      const seg = (a, b) => children.push({ type: "line", shape: { x1: a[0], y1: a[1], x2: b[0], y2: b[1] }, style });
      const [x, y, xl, xh, yl, yh] = [0, 1, 2, 3, 4, 5].map((i) => api.value(i));
      if (Number.isFinite(yl) && Number.isFinite(yh)) {
        const a = api.coord([x, yl]), b = api.coord([x, yh]);
        seg(a, b); seg([a[0] - 3, a[1]], [a[0] + 3, a[1]]); seg([b[0] - 3, b[1]], [b[0] + 3, b[1]]);
      }
      if (Number.isFinite(xl) && Number.isFinite(xh)) {
        const a = api.coord([xl, y]), b = api.coord([xh, y]);
        seg(a, b); seg([a[0], a[1] - 3], [a[0], a[1] + 3]); seg([b[0], b[1] - 3], [b[0], b[1] + 3]);
      }
      return { type: "group", children };
    },
  };
}

// A horizontal band (e.g. +-2 standardised residuals, the noise band) as a markArea on a series.
export function band(low, high, colour = "rgba(7,148,85,0.10)", label = "") {
  return { silent: true, itemStyle: { color: colour }, label: { show: !!label, position: "insideTopRight", color: "#667085" },
    data: [[{ yAxis: low, name: label }, { yAxis: high }]] };
}
