// The iteration's design and fitted response surfaces: ANOVA tables (with lack of fit and curvature)
// under a factor legend, since the table's rows name factors by letter (A, B, AB, ...).
import { fmt, h, table, wideTable } from "./core.js";
import { humanText, keyText } from "./labels.js";

function legend(factors) {
  return h("p", { className: "legend" }, h("b", {}, "Factors: "),
    factors.map((f, i) => h("span", {}, i ? "; " : "", h("b", {}, f.letter), ` = ${f.name}${f.unit ? " (" + f.unit + ")" : ""} ${fmt(f.low)} – ${fmt(f.high)}${f.log ? ", log" : ""}`)));
}

const ROW_CLASS = { "Lack of Fit": "lof", Curvature: "curvature", Model: "model-row", "Cor Total": "total-row" };

export function modelsSection(models) {
  const entries = Object.entries(models);
  if (!entries.length) return "";
  const first = entries.find(([, m]) => m.ok)?.[1];
  return h("section", { className: "card models" }, h("h3", {}, "Fitted response surfaces (ANOVA)"),
    first ? legend(first.fit.factors) : "",
    entries.map(([name, m]) => h("details", { open: entries.length <= 3 }, h("summary", {}, keyText(name), m.ok ? ` — R² ${fmt(m.fit.fit_statistics.r_squared, 4)}` : " — not fitted"),
      m.ok ? [h("p", {}, h("code", { className: "equation" }, m.fit.equation_natural)),
        h("div", { className: "scroll" }, table(["Source", "Sum of squares", "df", "Mean square", "F", "p"],
          m.fit.anova.map((r) => [h("span", { className: ROW_CLASS[r.source] || "" }, r.source), r.sum_of_squares, String(r.df), r.mean_square, r.f_value, r.p_value]))),
        h("p", { className: "muted" }, `R² ${fmt(m.fit.fit_statistics.r_squared)}, adjusted ${fmt(m.fit.fit_statistics.adj_r_squared)}, predicted ${fmt(m.fit.fit_statistics.pred_r_squared)}; pure-error sd ${fmt(m.pure_error_sd)} (simulator noise from the centre replicates)`),
        m.fit.messages.map((msg) => h("p", { className: "muted" }, msg))]
        : h("p", { className: "bad" }, humanText(m.error)))));
}

export function designSection(design) {
  const names = design.factors.map((f) => f.name);
  const letters = design.factors.map((f) => f.letter);
  const chains = (design.aliases?.chains || []).filter((ch) => ch.aliases.length);
  return h("section", { className: "card design" }, h("h3", {}, `Design: ${design.kind}${design.resolution_label ? ", " + design.resolution_label : ""}`),
    legend(design.factors),
    chains.length ? h("p", {}, `Aliases: ${chains.map((ch) => ch.label).join("; ")}`) : "",
    h("details", {}, h("summary", {}, `${design.runs.length} runs (natural units; coded levels in brackets)`),
      wideTable(["Std", "Run", "Type", "Seed", ...letters.map((l, i) => `${l}: ${names[i]}`)],
        design.runs.map((r) => [String(r.std_order), String(r.run_order), r.point_type, String(r.seed),
          ...names.map((n) => `${fmt(r.natural[n])} (${fmt(r.coded[n], 2)})`)]))));
}
