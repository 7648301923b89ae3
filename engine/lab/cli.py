"""`demcal run SPEC`: run one virtual-lab test or a battery from a JSON or YAML job spec.

The result record goes to stdout as JSON (so it can be piped or stored); progress and
errors go to stderr. A spec that does not parse or validate exits with status 2 and names
the offending field, never a traceback.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from pydantic import ValidationError

from engine.lab.spec import JobSpec


class SpecError(ValueError):
    """The spec file cannot be read, parsed or validated."""


def load_spec(path: str | Path) -> JobSpec:
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise SpecError(f"cannot read spec {path}: {exc.strerror or exc}") from None
    try:
        if path.suffix.lower() in (".yaml", ".yml"):
            import yaml

            data = yaml.safe_load(text)
        else:
            data = json.loads(text)
    except Exception as exc:  # json/yaml parser errors carry line and column
        raise SpecError(f"spec {path} is not valid {'YAML' if path.suffix.lower() in ('.yaml', '.yml') else 'JSON'}: {exc}") from None
    if not isinstance(data, dict):
        raise SpecError(f"spec {path} must be a mapping of fields (test, fidelity, seed, parameters, options)")
    try:
        # YAML 1.1 reads 2e6 (no decimal point) as a string: a hand-written spec file keeps lax number
        # parsing; JSON, like the API, is strict (no false for a number)
        return JobSpec.model_validate(data, strict=False if path.suffix.lower() in (".yaml", ".yml") else None)
    except ValidationError as exc:
        lines = [
            f"  {'.'.join(str(p) for p in err['loc']) or '(root)'}: {err['msg']}" for err in exc.errors()
        ]
        raise SpecError(f"invalid spec {path}:\n" + "\n".join(lines)) from None


def _progress_printer(fraction: float, phase: str) -> None:
    print(f"[{fraction * 100:5.1f} %] {phase}", file=sys.stderr, flush=True)


def _cmd_run(args: argparse.Namespace) -> int:
    try:
        spec = load_spec(args.spec)
    except SpecError as exc:
        print(f"demcal run: {exc}", file=sys.stderr)
        return 2
    from engine.lab import run_job

    try:
        result = run_job(spec, progress=_progress_printer if args.progress else None)
    except ValueError as exc:  # physically impossible or unsupported request
        print(f"demcal run: {exc}", file=sys.stderr)
        return 2
    text = result.model_dump_json(indent=args.indent)
    if args.output:
        Path(args.output).write_text(text)
    else:
        print(text)
    return 0


def register(subparsers) -> None:
    run = subparsers.add_parser(
        "run",
        help="run a virtual-lab test or battery from a JSON/YAML job spec",
        description="Run a virtual-lab test or battery (docs/lab.md) and print its result record as JSON.",
    )
    run.add_argument("spec", help="job spec file (.json, .yaml or .yml), e.g. docs/examples/screening-battery.json")
    run.add_argument("--progress", action="store_true", help="print progress to stderr")
    run.add_argument("--indent", type=int, default=None, help="indent the JSON output")
    run.add_argument("--output", "-o", default=None, help="write the result to this file instead of stdout")
    run.set_defaults(func=_cmd_run)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="demcal-lab", description="demcal virtual laboratory")
    sub = parser.add_subparsers(dest="command", required=True)
    register(sub)
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
