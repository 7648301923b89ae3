"""Plain-text tables for the CLI and `.summary()`; no logic lives here."""
from __future__ import annotations

import math


def fmt(v, digits: int = 5) -> str:
    if v is None:
        return "-"
    if isinstance(v, str):
        return v
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    if not math.isfinite(v):
        return "-"
    if v == 0:
        return "0"
    a = abs(v)
    if a >= 1e6 or a < 1e-4:
        return f"{v:.{digits - 1}e}"
    return f"{v:.{digits}g}"


def fmt_p(p) -> str:
    if p is None or not math.isfinite(p):
        return "-"
    return "< 0.0001" if p < 1e-4 else f"{p:.4f}"


def table(headers: list[str], rows: list[list], title: str = "") -> str:
    cells = [[c if isinstance(c, str) else fmt(c) for c in r] for r in rows]
    widths = [max(len(h), *(len(r[i]) for r in cells)) if cells else len(h) for i, h in enumerate(headers)]
    line = "  ".join(h.ljust(w) for h, w in zip(headers, widths))
    out = [title] if title else []
    out += [line, "-" * len(line)]
    out += ["  ".join(c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths)))
            for r in cells]
    return "\n".join(out)


def design_text(design) -> str:
    fac = design.factors
    head = [f"{design.kind}: {design.n_runs} runs, seed {design.base_seed}"]
    head += [f"  {f.letter}: {f.name} [{f.unit or '-'}] low {fmt(f.low)} high {fmt(f.high)}"
             + (" (log scale)" if f.log else "") for f in fac]
    if design.generators:
        head.append("Generators: " + ", ".join(design.generators))
    recs = design.records("std")
    headers = ["Std", "Run", "Block", "Type", "Rep", "Seed"] + [f.name for f in fac] + [f.letter for f in fac]
    rows = [[str(r["std_order"]), str(r["run_order"]), str(r["block"]), r["point_type"], str(r["replicate"]),
             str(r["seed"])] + [r[f.name] for f in fac] + [_coded_text(r[f.letter + "_coded"]) for f in fac]
            for r in recs]
    parts = ["\n".join(head), table(headers, rows)]
    if design.aliases is not None:
        parts.append("Alias structure\n" + "\n".join("  " + s for s in design.aliases.summary_lines()))
    if design.notes:
        parts.append("Notes\n" + "\n".join("  " + s for s in design.notes))
    return "\n\n".join(parts)


def _coded_text(v: float) -> str:
    return "0" if v == 0 else f"{v:+.4g}"
