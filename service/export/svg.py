"""Charts as inline SVG text, drawn in Python: the shareable report (``report_html``) needs pictures that
travel inside one HTML file and show offline, with no script or library.

Two charts, each a function of plain numbers: a parity plot (measured against confirmed, with the
measurement's +-2u and the prediction interval as error bars, one panel per unit) and an error
history (a line per iteration with the noise band shaded). Every text is escaped.
"""
from __future__ import annotations

import math
from html import escape

WIDTH, HEIGHT = 300, 260
MARGIN_L, MARGIN_R, MARGIN_T, MARGIN_B = 58, 12, 26, 40


def _fmt(value: float) -> str:
    return f"{value:.4g}"


def nice_ticks(low: float, high: float, count: int = 5) -> list[float]:
    """Round tick values covering [low, high] (steps of 1, 2 or 5 times a power of ten)."""
    if not (math.isfinite(low) and math.isfinite(high)) or high <= low:
        return [low]
    raw = (high - low) / max(count - 1, 1)
    power = 10 ** math.floor(math.log10(raw))
    step = next(m * power for m in (1, 2, 5, 10) if m * power >= raw)
    start = math.ceil(low / step - 1e-9) * step
    ticks, value = [], start
    while value <= high + 1e-9 * step:
        ticks.append(round(value, 12))
        value += step
    return ticks


class _Frame:
    """A plot area with linear scales from data to pixels (y up)."""

    def __init__(self, x_range, y_range, width=WIDTH, height=HEIGHT, top=MARGIN_T):
        self.x0, self.x1 = x_range
        self.y0, self.y1 = y_range
        self.width, self.height, self.top = width, height, top

    def x(self, value: float) -> float:
        span = (self.x1 - self.x0) or 1.0
        return MARGIN_L + (value - self.x0) / span * (self.width - MARGIN_L - MARGIN_R)

    def y(self, value: float) -> float:
        span = (self.y1 - self.y0) or 1.0
        return self.height - MARGIN_B - (value - self.y0) / span * (self.height - self.top - MARGIN_B)

    def axes(self, title: str, x_label: str, y_label: str, x_ticks=None, y_ticks=None) -> list[str]:
        left, right = MARGIN_L, self.width - MARGIN_R
        top, bottom = self.top, self.height - MARGIN_B
        out = [f'<rect x="{left}" y="{top}" width="{right - left}" height="{bottom - top}" class="frame"/>',
               f'<text x="{self.width / 2:.1f}" y="16" class="title">{escape(title)}</text>',
               f'<text x="{(left + right) / 2:.1f}" y="{self.height - 6}" class="label">{escape(x_label)}</text>',
               f'<text x="14" y="{(top + bottom) / 2:.1f}" class="label" '
               f'transform="rotate(-90 14 {(top + bottom) / 2:.1f})">{escape(y_label)}</text>']
        for t in x_ticks if x_ticks is not None else nice_ticks(self.x0, self.x1):
            px = self.x(t)
            if left - 0.5 <= px <= right + 0.5:
                out.append(f'<line x1="{px:.1f}" y1="{bottom}" x2="{px:.1f}" y2="{bottom + 4}" class="axis"/>'
                           f'<text x="{px:.1f}" y="{bottom + 15}" class="tick">{escape(_fmt(t))}</text>')
        for t in y_ticks if y_ticks is not None else nice_ticks(self.y0, self.y1):
            py = self.y(t)
            if top - 0.5 <= py <= bottom + 0.5:
                out.append(f'<line x1="{left - 4}" y1="{py:.1f}" x2="{left}" y2="{py:.1f}" class="axis"/>'
                           f'<text x="{left - 6}" y="{py + 3:.1f}" class="tick-y">{escape(_fmt(t))}</text>')
        return out


def _svg(body: list[str], label: str, width=WIDTH, height=HEIGHT) -> str:
    return (f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" '
            f'role="img" aria-label="{escape(label)}">' + "".join(body) + "</svg>")


def _padded(values: list[float]) -> tuple[float, float]:
    low, high = min(values), max(values)
    pad = 0.08 * (high - low) if high > low else 0.05 * abs(high) or 1.0
    return low - pad, high + pad


def parity_plot(points: list[dict], unit: str) -> str:
    """Measured (x) against confirmed (y) for the targets of one unit, on the diagonal where they agree.

    ``points``: dicts with ``label``, ``measured``, ``u`` (standard uncertainty or None), ``confirmed`` and
    ``interval`` ((low, high) of the prediction for the confirmed mean, or None)."""
    spread = []
    for p in points:
        spread += [p["measured"], p["confirmed"]]
        if p.get("u"):
            spread += [p["measured"] - 2 * p["u"], p["measured"] + 2 * p["u"]]
        if p.get("interval") and None not in p["interval"]:
            spread += list(p["interval"])
    low, high = _padded(spread)
    f = _Frame((low, high), (low, high))
    body = f.axes(f"simulated vs measured [{unit}]", f"measured [{unit}]", f"confirmed [{unit}]")
    body.append(f'<line x1="{f.x(low):.1f}" y1="{f.y(low):.1f}" x2="{f.x(high):.1f}" y2="{f.y(high):.1f}" class="diagonal"/>')
    for p in points:
        x, y = f.x(p["measured"]), f.y(p["confirmed"])
        if p.get("u"):
            body.append(f'<line x1="{f.x(p["measured"] - 2 * p["u"]):.1f}" y1="{y:.1f}" '
                        f'x2="{f.x(p["measured"] + 2 * p["u"]):.1f}" y2="{y:.1f}" class="bar"/>')
        if p.get("interval") and None not in p["interval"]:
            body.append(f'<line x1="{x:.1f}" y1="{f.y(p["interval"][0]):.1f}" x2="{x:.1f}" '
                        f'y2="{f.y(p["interval"][1]):.1f}" class="bar"/>')
        body.append(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="4" class="point"><title>{escape(p["label"])}: measured '
                    f'{escape(_fmt(p["measured"]))}, confirmed {escape(_fmt(p["confirmed"]))} {escape(unit)}</title></circle>')
    return _svg(body, f"parity plot, {unit}")


def error_history(entries: list[dict]) -> str:
    """The weighted error (RMS of the standardised residuals) per iteration, with the lack of fit's noise
    band of chi2/dof where the report has one. ``entries``: ``number``, ``weighted_rms``, ``chi2_per_dof``,
    ``noise_band``."""
    width = max(WIDTH, 90 * len(entries) + MARGIN_L)
    numbers = [e["number"] for e in entries]
    rms = [e.get("weighted_rms") for e in entries]
    chi = [e.get("chi2_per_dof") for e in entries]
    bands = [e.get("noise_band") for e in entries]
    values = [v for v in rms + chi if v is not None] + [b[1] for b in bands if b] + [0.0]
    # the legend gets a strip of its own between the title and the plot
    legend_y = MARGIN_T + 6
    f = _Frame((min(numbers) - 0.5, max(numbers) + 0.5), (0.0, _padded(values)[1]), width=width,
               height=HEIGHT + 18, top=MARGIN_T + 18)
    body = f.axes("weighted error per iteration", "iteration", "RMS z, chi2/dof", x_ticks=numbers)
    for n, band in zip(numbers, bands):
        if band:
            body.append(f'<rect x="{f.x(n - 0.4):.1f}" y="{f.y(band[1]):.1f}" width="{f.x(n + 0.4) - f.x(n - 0.4):.1f}" '
                        f'height="{f.y(band[0]) - f.y(band[1]):.1f}" class="band"><title>iteration {n}: chi2/dof noise '
                        f'band [{escape(_fmt(band[0]))}, {escape(_fmt(band[1]))}]</title></rect>')
    for series, css, name in ((rms, "line", "RMS z"), (chi, "line2", "chi2/dof")):
        pts = [(n, v) for n, v in zip(numbers, series) if v is not None]
        if len(pts) > 1:
            body.append(f'<polyline class="{css}" points="' + " ".join(f"{f.x(n):.1f},{f.y(v):.1f}" for n, v in pts) + '"/>')
        for n, v in pts:
            body.append(f'<circle cx="{f.x(n):.1f}" cy="{f.y(v):.1f}" r="3.5" class="{css}-point"><title>iteration {n}: '
                        f'{name} {escape(_fmt(v))}</title></circle>')
    for k, (css, name) in enumerate((("line", "RMS z"), ("line2", "chi2/dof"), ("band", "noise band"))):
        x = MARGIN_L + 8 + 78 * k
        mark = (f'<rect x="{x}" y="{legend_y - 7}" width="14" height="8" class="band"/>' if css == "band" else
                f'<line x1="{x}" y1="{legend_y - 3}" x2="{x + 14}" y2="{legend_y - 3}" class="{css}"/>')
        body.append(mark + f'<text x="{x + 18}" y="{legend_y}" class="legend">{name}</text>')
    return _svg(body, "error history", width=width, height=HEIGHT + 18)
