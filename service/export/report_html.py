"""The shareable report: a campaign's verdict, targets, diagnosis and history as one self-contained HTML file.

Why: engineers share results with colleagues who will not run a service. The file carries its own CSS
and its charts as inline SVG (``service.export.svg``), has no script, and references nothing outside
itself (no src or href leaves the file), so it reads the same offline, attached to an e-mail or archived.

Built from the API's own views (the summary, the iteration's report, the history), so it says what the
API says. Every text from the database is escaped.
"""
from __future__ import annotations

from collections import defaultdict
from html import escape
from typing import Any

from calibration.vocabulary import Verdict
from engine.lab.units import parameter_si_unit
from service.export import svg

CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:2rem auto;max-width:1100px;color:#1d2330;
 padding:0 1rem;line-height:1.4}
h1{font-size:1.5rem;margin-bottom:.2rem}h2{font-size:1.15rem;margin-top:2rem;border-bottom:1px solid #d6dbe4}
.sub{color:#5a6475}.verdict{padding:.8rem 1rem;border-radius:6px;background:#eef2f8;border-left:5px solid #3d6fb6}
.verdict.ok{background:#eaf6ee;border-color:#2e8b57}.verdict.bad{background:#fbeeee;border-color:#b33a3a}
.verdict strong{font-size:1.1rem}table{border-collapse:collapse;font-size:.88rem;margin:.5rem 0}
table{display:block;overflow-x:auto;max-width:100%}
th,td{border-bottom:1px solid #e2e6ee;padding:.25rem .55rem;text-align:left;vertical-align:top}
th{background:#f4f6fa}td.num{text-align:right;font-variant-numeric:tabular-nums}
.charts{display:flex;flex-wrap:wrap;gap:1rem}.note{color:#5a6475;font-size:.85rem}
svg{background:#fff;border:1px solid #e2e6ee}svg .frame{fill:none;stroke:#9aa3b2}svg .axis{stroke:#9aa3b2}
svg .tick{font-size:10px;fill:#5a6475;text-anchor:middle}svg .tick-y{font-size:10px;fill:#5a6475;text-anchor:end}
svg .legend{font-size:10px;fill:#1d2330;text-anchor:start}svg .title{font-size:12px;text-anchor:middle;fill:#1d2330}
svg .label{font-size:11px;text-anchor:middle;fill:#1d2330}svg .diagonal{stroke:#9aa3b2;stroke-dasharray:4 3}
svg .bar{stroke:#3d6fb6;stroke-width:1.4}svg .point{fill:#3d6fb6}svg .band{fill:#dfeadf}
svg .line{fill:none;stroke:#3d6fb6;stroke-width:2}svg .line-point{fill:#3d6fb6}
svg .line2{fill:none;stroke:#c07a1a;stroke-width:2;stroke-dasharray:5 3}svg .line2-point{fill:#c07a1a}
ul.warn li{color:#8a5a00}
"""


def _f(value: Any) -> str:
    if value is None:
        return "–"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.4g}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_f(v) for v in value) + "]"
    if isinstance(value, dict):
        return ", ".join(f"{k} = {_f(v)}" for k, v in value.items()) or "–"
    return str(value)


def _table(headers: list[str], rows: list[list[Any]], numeric: set[int] = frozenset()) -> str:
    head = "".join(f"<th>{escape(h)}</th>" for h in headers)
    body = "".join("<tr>" + "".join(f'<td{" class=num" if i in numeric else ""}>{escape(_f(c))}</td>'
                                    for i, c in enumerate(row)) + "</tr>" for row in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _verdict_class(verdict: str | None) -> str:
    return "ok" if verdict == Verdict.CALIBRATED else "bad" if verdict else ""


def _parameters(report: dict[str, Any], factors: list[dict], parameter_std: dict | None) -> str:
    ranges = {f["name"]: (f["low"], f["high"]) for f in factors}
    intervals = report.get("intervals") or {}
    rows = []
    for name, value in (report.get("optimum") or {}).items():
        row = (intervals.get("parameters") or {}).get(name) or {}
        sd = row.get("sd", (parameter_std or {}).get(name))
        ci = [row["low"], row["high"]] if row.get("low") is not None else None
        rows.append([name, value, parameter_si_unit(name.split(".")[-1]), sd, ci, ranges.get(name)])
    fixed = report.get("fixed_parameters") or {}
    text = _table(["parameter", "value", "unit", "standard uncertainty", "95 % interval", "design range"], rows,
                  {1, 3})
    if intervals.get("scaled_by_misfit"):
        text += (f'<p class="note">intervals widened by chi2/dof {escape(_f(intervals.get("scale")))}: the model '
                 "misses the measurements by more than their noise</p>")
    measured = intervals.get("measured_points") or {}
    if measured.get("widened"):
        text += (f'<p class="note">widened to the points measured on the batteries that fit within chi2 '
                 f'{escape(_f(measured.get("threshold")))} of the best: {escape(", ".join(measured["widened"]))}</p>')
    for trade in intervals.get("trades") or []:
        text += f'<p class="note">{escape(trade["message"])}</p>'
    if fixed:
        text += f'<p class="note">fixed by the campaign: {escape(_f(fixed))}</p>'
    return text


def _targets(report: dict[str, Any]) -> str:
    rows = [[t["test"], t["quantity"], t.get("condition") or {}, t.get("unit"), t.get("measured"),
             _f(t.get("measured_uncertainty")) + (" (assumed)" if t.get("uncertainty_assumed") else ""), t.get("predicted"), t.get("prediction_interval"), t.get("confirmed"),
             t.get("standardised_residual"), t.get("reachability"), t["status"]] for t in report.get("targets", [])]
    return _table(["test", "quantity", "condition", "unit", "measured", "u", "predicted", "95 % interval", "confirmed",
                   "z", "min |z| in box", "status"], rows, {4, 5, 6, 8, 9, 10})


def _parity_charts(report: dict[str, Any]) -> str:
    by_unit: dict[str, list[dict]] = defaultdict(list)
    for t in report.get("targets", []):
        if t.get("confirmed") is None or t.get("measured") is None:
            continue
        condition = ", ".join(f"{k} {v:g}" for k, v in (t.get("condition") or {}).items())
        by_unit[t.get("unit") or "1"].append({
            "label": f"{t['test']} {t['quantity']}" + (f" ({condition})" if condition else ""),
            "measured": t["measured"], "u": t.get("measured_uncertainty"), "confirmed": t["confirmed"],
            "interval": t.get("prediction_interval")})
    return "".join(svg.parity_plot(points, unit) for unit, points in sorted(by_unit.items()))


def _strength(row: dict[str, Any], diagnosis: dict[str, Any]) -> Any:
    """The strength as the CLI's diagnosis table and the page print it (``calibration.attribute.
    strength_reading``): the estimate, a switch's share, or why there is none."""
    from calibration.attribute import strength_reading

    value = strength_reading(row, diagnosis)
    if isinstance(value, str):
        return f"none ({value})"
    if value is not None and row.get("strength") is None:
        return f"{100 * value:.3g} % of the switch"
    return value


def _diagnosis(report: dict[str, Any]) -> str:
    d = report.get("diagnosis")
    if not d:
        return '<p class="note">No diagnosis in this iteration.</p>'
    rows = [[r["effect"], r.get("title"), r.get("lm"), r.get("p_holm"), r.get("explained"), _strength(r, d),
             r.get("unit"), r.get("plausible"), r.get("alias_group")] for r in d.get("ranking", [])]
    text = (f"<p><strong>{escape(_f(d.get('verdict')))}</strong>: {escape(_f(d.get('message')))}</p>"
            + _table(["effect", "physics", "LM", "Holm p", "explained", "strength", "unit", "plausible", "alias group"],
                     rows, {2, 3, 4, 5}))
    for g in d.get("alias_groups", []):
        text += f'<p class="note">alias group {escape(_f(g.get("group")))}: {escape(", ".join(g.get("effects", [])))}: ' \
                f'{escape(_f(g.get("message")))}</p>'
    if d.get("measure_next"):
        text += "<p>Measure next: " + escape("; ".join(d["measure_next"])) + "</p>"
    return text


def _history(history: dict[str, Any]) -> str:
    entries = history.get("iterations", [])
    if not entries:
        return ""
    rows = [[e["number"], ", ".join(e.get("effects") or []) or "–", e.get("weighted_rms"), e.get("chi2_per_dof"),
             e.get("noise_band"), e.get("verdict"), ", ".join(e.get("effect_added_next") or []) or "–",
             e.get("stop_reason")] for e in entries]
    return (f'<div class="charts">{svg.error_history(entries)}</div>'
            + _table(["iteration", "effects", "RMS z", "chi2/dof", "noise band", "verdict", "added next", "stopped"],
                     rows, {2, 3}))


def render(*, summary: dict[str, Any], report: dict[str, Any], iteration: int, history: dict[str, Any],
           material_name: str, parameter_std: dict | None, factors: list[dict], demcal_version: str) -> str:
    """The report of ``iteration`` (its report, design ``factors`` and the parameters' standard
    uncertainties; the campaign's summary and history) as one HTML document."""
    verdict = report.get("verdict")
    lof = report.get("lack_of_fit")
    lof_text = (f"lack of fit: chi2 {_f(lof['statistic'])} on {_f(lof['dof'])} dof (per dof {_f(lof['chi2_per_dof'])}, "
                f"noise band {_f(lof['noise_band'])}), p {_f(lof['p_value'])}") if lof else ""
    stop = summary.get("stop_reason")
    warnings = report.get("warnings") or []
    title = f"demcal report: {summary['name']}"
    parts = [
        "<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{escape(title)}</title><style>{CSS}</style></head><body>",
        f"<h1>{escape(title)}</h1>",
        f'<p class="sub">campaign {summary["id"]} · material {escape(material_name)} (#{summary["material_id"]}) · '
        f'evaluator {escape(str(summary["evaluator"]))} · fidelity {escape(str(summary["fidelity"]))} · iteration '
        f'{iteration} of {summary["current_iteration"]} · status {escape(str(summary["status"]))}'
        + (f' · finished {escape(summary["finished_at"])}' if summary.get("finished_at") else "") + "</p>",
        f'<div class="verdict {_verdict_class(verdict)}" id="verdict"><strong>{escape(_f(verdict))}</strong>'
        f'<p>{escape(_f(report.get("meaning")))}</p>'
        + (f'<p class="note">{escape(lof_text)}</p>' if lof_text else "")
        + (f'<p class="note">automatic mode stopped: {escape(stop)}</p>' if stop else "") + "</div>",
        "<h2>Calibrated parameters</h2>", _parameters(report, factors, parameter_std),
        '<h2 id="targets">Targets</h2>', _targets(report),
        f'<div class="charts" id="parity">{_parity_charts(report)}</div>',
        '<p class="note">Error bars: measured ± 2 standard uncertainties (horizontal), the 95 % prediction interval '
        'of the confirmed mean (vertical); on the dashed diagonal the model reproduces the measurement.</p>',
        '<h2 id="diagnosis">Diagnosis</h2>', _diagnosis(report),
        '<h2 id="history">History</h2>', _history(history),
    ]
    if warnings:
        parts.append("<h2>Warnings</h2><ul class=warn>" + "".join(f"<li>{escape(w)}</li>" for w in warnings) + "</ul>")
    parts.append(f'<p class="note">Written by demcal {escape(demcal_version)}: one self-contained file, no scripts and '
                 "nothing loaded from elsewhere.</p></body></html>")
    return "\n".join(parts) + "\n"
