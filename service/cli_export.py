"""``demcal campaign export ID --format NAME``, ``demcal material card ID`` and ``demcal material import-card FILE``.

Exports are files, not JSON views: the commands fetch the service's text (a material card in YAML or
JSON, or any other registered format: ``GET /api/v1/export-formats``) and write it to ``--output`` or
stdout. The import reads a card in YAML or JSON and posts it as JSON. Errors are one line on stderr
and exit status 2, as for every client command (service.cli_http).
"""
from __future__ import annotations

import sys
from pathlib import Path

import httpx

from service.cli_http import POINT_ELSEWHERE, CliError, client, service_url
from service.cli_http import call as _call
from service.cli_http import emit as _emit
from service.cli_http import leaf as _leaf


def _text(args, path: str, params: dict) -> str:
    """The body of a GET as text; an HTTP error as the API's first message, like ``cli_http.call``."""
    url, source = service_url(args)
    try:
        with client(args, url) as http:
            response = http.get(path, params=params)
    except httpx.HTTPError as exc:
        raise CliError(f"cannot reach the service at {url} (from {source}): {exc}; {POINT_ELSEWHERE}") from exc
    if response.status_code >= 400:
        try:
            first = response.json()["detail"][0]
            where = ".".join(str(p) for p in first.get("loc", []))
            message = first.get("msg") + (f" (at {where})" if where else "")
        except (ValueError, KeyError, IndexError, TypeError, AttributeError):
            message = response.text[:200]
        raise CliError(f"HTTP {response.status_code}: {message}")
    return response.text


def _write(text: str, output: str | None, what: str) -> int:
    if output is None or output == "-":
        sys.stdout.write(text)
        return 0
    try:
        Path(output).write_text(text, encoding="utf-8")
    except OSError as exc:
        raise CliError(f"cannot write {output}: {exc}") from exc
    print(f"{what} written to {output}", file=sys.stderr)
    return 0


def campaign_export(args) -> int:
    params = {"format": args.format}
    if args.iteration:
        params["number"] = args.iteration
    text = _text(args, f"/campaigns/{args.id}/export", params)
    return _write(text, args.output, f"campaign {args.id} ({args.format})")


def material_card(args) -> int:
    text = _text(args, f"/materials/{args.id}/material-card", {"format": args.format})
    return _write(text, args.output, f"material {args.id}'s card")


def material_import_card(args) -> int:
    from service.export.card import CardError, load_text

    try:
        text = sys.stdin.read() if args.file == "-" else Path(args.file).read_text(encoding="utf-8")
        data = load_text(text)
    except OSError as exc:
        raise CliError(f"cannot read {args.file}: {exc}") from exc
    except CardError as exc:
        raise CliError(f"{args.file}: {exc}") from exc
    if not isinstance(data, dict):
        raise CliError(f"{args.file}: a material card is a mapping (YAML or JSON object), not {type(data).__name__}")
    m = _call(args, "POST", "/materials/import-card", data, params={"name": args.name} if args.name else None)
    return _emit(args, m, f"material {m['id']}: {m['name']} (from a material card, "
                          f"{len(m['measurements'])} measurements)")


def campaign_verify_export(args) -> int:
    """Fetch the campaign's material card from the service, then run the LIGGGHTS proof here: the exported
    material in LIGGGHTS and demcal's own lab on the screening fill and confined compression, ``--packings``
    each (calibration.export.verify). Minutes per packing; LIGGGHTS must be installed on this machine."""
    from calibration.export.material import from_micro_parameters
    from calibration.export.rig_liggghts import liggghts_executable
    from calibration.export.verify import verify_export
    from service.export.card import CardError, load_text, micro_parameters, validate

    if liggghts_executable() is None:
        raise CliError("LIGGGHTS is not installed here (apt-get install liggghts): the proof runs it")
    params = {"number": args.iteration} if args.iteration else {}
    try:
        card = validate(load_text(_text(args, f"/campaigns/{args.id}/material-card", params)))
    except CardError as exc:
        raise CliError(f"campaign {args.id}'s material card: {exc}") from exc
    if card.rig.fidelity != "screening":  # calibration.export.verify builds the screening rig in LIGGGHTS
        where = card.rig.fidelity or f"resolution {card.rig.resolution} in its material's rig"
        raise CliError(f"campaign {args.id} was calibrated at {where}; the LIGGGHTS proof runs the screening rig "
                       "only (docs/export.md), so it would compare the material in another apparatus")
    material = from_micro_parameters(micro_parameters(card), card.rig.fidelity)
    report = verify_export(material, seeds=tuple(range(1, args.packings + 1)),
                           progress=lambda message: print(message, file=sys.stderr, flush=True))
    _emit(args, report.to_dict(), report.text())
    return 0 if report.holds else 1


def register_campaign(csub) -> None:
    """``demcal campaign export``; ``csub``: the campaign command's subparsers."""
    export = _leaf(csub, "export", campaign_export, "the calibrated material as a file: the material card "
                   "(docs/export.md) or another registered format")
    export.add_argument("id", type=int)
    export.add_argument("--format", default="card",
                        help="card (YAML, default), card-json, or another format the service lists at "
                             "GET /api/v1/export-formats")
    export.add_argument("--output", "-o", help="file to write (default stdout)")
    export.add_argument("--iteration", type=int, help="a calibrated iteration (default the model the loop keeps)")
    verify = _leaf(csub, "verify-export", campaign_verify_export, "run the LIGGGHTS export of the calibrated "
                   "material beside demcal's own lab (fill, confined compression) and say whether the hand-off "
                   "holds (exit 1 when it does not)")
    verify.add_argument("id", type=int)
    verify.add_argument("--packings", type=int, default=3, choices=range(1, 11), metavar="N",
                        help="packings per engine (default 3)")
    verify.add_argument("--iteration", type=int, help="a calibrated iteration (default the model the loop keeps)")


def register_material(msub) -> None:
    """``demcal material import-card`` and ``demcal material card``; ``msub``: the material command's subparsers."""
    imp = _leaf(msub, "import-card", material_import_card, "create a material with fixed parameters from a "
                "material card (YAML or JSON)", creates=True)
    imp.add_argument("file", help="the card, '-' for stdin")
    imp.add_argument("--name", help="the new material's name (default the card's)")
    card = _leaf(msub, "card", material_card, "the material card of a material imported from one")
    card.add_argument("id", type=int)
    card.add_argument("--format", choices=["yaml", "json"], default="yaml")
    card.add_argument("--output", "-o", help="file to write (default stdout)")
