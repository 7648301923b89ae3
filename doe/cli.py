"""`demcal doe design|analyze`: designs and their analysis from the command line.

`service.cli` calls `register(subparsers)`; `python -m doe.cli` runs it alone.
Bad input prints one line on stderr and returns exit code 2.
"""
from __future__ import annotations

import argparse
import csv
import io
import json
import math
import sys

from typing import TYPE_CHECKING

from .factors import DoeError, Factor, parse_factor

if TYPE_CHECKING:  # pyDOE3 and statsmodels take ~2 s to import: only the commands that use them pay
    from .designs import Design


def _err(msg: str) -> int:
    print(f"demcal doe: error: {msg}", file=sys.stderr)
    return 2


def _split(values) -> list[str]:
    out = []
    for v in values or []:
        out += [s.strip() for s in v.split(",") if s.strip()]
    return out


def _design_cmd(args) -> int:
    from .designs import augment_ccd, foldover, make_design

    try:
        factors = [parse_factor(f) for f in args.factor]
        gens = _split(args.generators) if args.generators is not None else None
        design = make_design(factors, gens, full=args.full, center_runs=args.center, replicates=args.replicates,
                             seed=args.seed, randomize=not args.no_randomize)
        if args.foldover:
            design = foldover(design, args.foldover)
        if args.ccd:
            design = augment_ccd(design, args.ccd, args.ccd_center)
    except DoeError as exc:
        return _err(str(exc))
    if args.format == "json":
        print(json.dumps(design.to_dict(), indent=2))
    elif args.format == "csv":
        print(design_csv(design), end="")
    else:
        print(design.summary())
    return 0


def design_csv(design: "Design") -> str:
    """Runs as CSV; alias structure and notes as leading '#' comment lines."""
    buf = io.StringIO()
    lines = [f"{design.kind}; seed {design.base_seed}"]
    lines += [f"{f.letter} = {f.name} [{f.unit}] low {f.low:g} high {f.high:g}" for f in design.factors]
    if design.aliases is not None:
        lines += design.aliases.summary_lines()
    lines += design.notes
    for s in lines:
        buf.write(f"# {s}\n")
    recs = design.records("std")
    w = csv.DictWriter(buf, fieldnames=list(recs[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(recs)
    return buf.getvalue()


def read_runs_csv(path: str) -> list[dict[str, str]]:
    try:
        with open(path, newline="") as fh:
            text = "".join(line for line in fh if not line.lstrip().startswith("#"))
    except OSError as exc:
        raise DoeError(f"cannot read {path}: {exc.strerror}") from None
    rows = list(csv.DictReader(io.StringIO(text)))
    if not rows:
        raise DoeError(f"{path} has no data rows")
    return rows


def _number(row_no: int, col: str, text) -> float:
    if text is None:
        raise DoeError(f"row {row_no}: no column {col!r}")
    if text.strip() == "":
        return math.nan
    try:
        return float(text)
    except ValueError:
        raise DoeError(f"row {row_no}, column {col!r}: {text!r} is not a number") from None


def _analyze_cmd(args) -> int:
    from .designs import Design
    from .fit import fit_response

    try:
        rows = read_runs_csv(args.file)
        specs = _split([args.factors])
        responses = _split([args.responses])
        if not specs or not responses:
            raise DoeError("give --factors and --responses as comma-separated names")
        columns = set(rows[0])
        factors = []
        for spec in specs:
            name = spec.split(":")[0]
            if name not in columns:
                raise DoeError(f"factor column {name!r} not in {args.file} (columns: {', '.join(rows[0])})")
            if ":" in spec:
                factors.append(parse_factor(spec))
                continue
            vals = [_number(i + 2, name, r.get(name)) for i, r in enumerate(rows)]
            if any(math.isnan(v) for v in vals):
                raise DoeError(f"factor column {name!r} has empty cells")
            factors.append(Factor(name, min(vals), max(vals)))
        for r in responses:
            if r not in columns:
                raise DoeError(f"response column {r!r} not in {args.file} (columns: {', '.join(rows[0])})")
        natural = [{f.name: _number(i + 2, f.name, row.get(f.name)) for f in factors} for i, row in enumerate(rows)]
        design = Design.from_runs(factors, natural)
        terms = _split([args.terms]) if args.terms else None
        fits = {}
        for r in responses:
            y = [_number(i + 2, r, row.get(r)) for i, row in enumerate(rows)]
            fit = fit_response(design, y, terms, r, args.alpha)
            if args.reduce:
                fit = fit.reduce(args.alpha_out)
            fits[r] = fit
    except DoeError as exc:
        return _err(str(exc))
    if args.json:
        print(json.dumps({"factors": [f.to_dict() for f in design.factors],
                          "aliases": design.aliases.to_dict() if design.aliases else None,
                          "responses": {r: f.to_dict() for r, f in fits.items()}}, indent=2))
    else:
        head = [f"{len(rows)} runs from {args.file}"]
        head += [f"  {f.letter}: {f.name} low {f.low:g} high {f.high:g}" for f in design.factors]
        if design.aliases is not None:
            head += ["Alias structure"] + ["  " + s for s in design.aliases.summary_lines()]
        print("\n".join(head))
        for fit in fits.values():
            print("\n" + "=" * 72 + "\n" + fit.summary())
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("doe", help="design of experiments: make designs, analyse runs")
    sub = p.add_subparsers(dest="doe_command", metavar="{design,analyze}")
    sub.required = True

    d = sub.add_parser("design", help="print a two-level design (natural and coded units, aliases)")
    d.add_argument("--factor", action="append", required=True, metavar="NAME:LOW:HIGH[:UNIT][:log]",
                   help="one factor; repeat for each (order gives letters A, B, ...)")
    d.add_argument("--generators", nargs="*", metavar="D=ABC",
                   help="fraction generators (default D=ABC for four factors; none given = full factorial)")
    d.add_argument("--full", action="store_true", help="full factorial")
    d.add_argument("--center", type=int, default=0, metavar="N", help="centre runs, each with its own seed")
    d.add_argument("--replicates", type=int, default=1, metavar="N")
    d.add_argument("--seed", type=int, default=0, help="seed for run order and simulator seeds")
    d.add_argument("--no-randomize", action="store_true", help="run order = standard order")
    d.add_argument("--foldover", metavar="FACTOR", help="add a fold-over on this factor")
    d.add_argument("--ccd", choices=["face", "rotatable"], help="augment to a central composite design")
    d.add_argument("--ccd-center", type=int, default=2, metavar="N", help="centre runs in the axial block")
    d.add_argument("--format", choices=["text", "csv", "json"], default="text")
    d.set_defaults(func=_design_cmd)

    a = sub.add_parser("analyze", help="effects, coefficients and ANOVA from a CSV of runs")
    a.add_argument("file", help="CSV: one row per run, factor columns in natural units, response columns")
    a.add_argument("--factors", required=True, metavar="NAMES",
                   help="comma-separated factor columns; NAME:LOW:HIGH gives levels instead of the data range")
    a.add_argument("--responses", required=True, metavar="NAMES", help="comma-separated response columns")
    a.add_argument("--terms", metavar="TERMS", help="model terms, e.g. A,B,AB (default: estimable mains and 2FIs)")
    a.add_argument("--reduce", action="store_true", help="hierarchical backward reduction")
    a.add_argument("--alpha", type=float, default=0.05)
    a.add_argument("--alpha-out", type=float, default=0.10)
    a.add_argument("--json", action="store_true", help="JSON instead of tables")
    a.set_defaults(func=_analyze_cmd)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="demcal")
    subs = parser.add_subparsers(dest="command")
    subs.required = True
    register(subs)
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
