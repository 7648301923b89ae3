"""``demcal rig list|show|create``: the apparatus records (engine.lab.rigs), through the HTTP API.

The same calls as GET/POST /api/v1/rigs; errors are one line on stderr and exit status 2 (service.cli_http).
"""
from __future__ import annotations

from service.cli_http import call, emit, leaf, page_footer, page_options, page_params, read_json, table


def _box(r: dict) -> str:
    box = r.get("shear_box")
    if not box:
        return "-"
    return (f"{1000 * box['container_diameter_m']:g} mm, halves {1000 * box['bottom_half_height_m']:g}"
            f"/{1000 * box['top_half_height_m']:g} mm, gap {1000 * box['gap_m']:g} mm")


def _warnings(r: dict) -> str:
    return "".join(f"\nwarning: {w}" for w in r.get("warnings") or [])


def rig_list(args) -> int:
    data = call(args, "GET", "/rigs", params=page_params(args))
    rows = [[r["id"], r["name"], _box(r), ", ".join(k for k in ("shear_box", "fill", "angle_of_repose", "anchor")
                                                     if r.get(k)), r["bundled"]] for r in data["items"]]
    return emit(args, data, table(["id", "name", "shear box", "sections", "bundled"], rows) + page_footer(data))


def _params(args) -> dict:
    return {"material_id": args.material} if args.material is not None else {}


def rig_show(args) -> int:
    r = call(args, "GET", f"/rigs/{args.id}", params=_params(args))
    lines = [f"{r['name']} (#{r['id']}{', bundled, read-only' if r['bundled'] else ''})", r.get("description", "")]
    for section in ("shear_box", "fill", "angle_of_repose", "anchor"):
        if r.get(section):
            lines.append(f"\n{section}:")
            lines += [f"  {k} = {v}" for k, v in r[section].items()]
    return emit(args, r, "\n".join(lines) + _warnings(r))


def rig_create(args) -> int:
    body = read_json(args.file)
    if args.name is not None:
        body["name"] = args.name
    r = call(args, "POST", "/rigs", body, params=_params(args))
    return emit(args, r, f"rig {r['id']}: {r['name']} ({_box(r)})" + _warnings(r))


def register(subparsers) -> None:
    rig = subparsers.add_parser("rig", help="rigs: the apparatus measurements were made in")
    rsub = rig.add_subparsers(dest="rig_command", required=True)
    page_options(leaf(rsub, "list", rig_list, "list rigs (the bundled ones are read-only)"))
    show = leaf(rsub, "show", rig_show, "show a rig's record (SI)")
    show.add_argument("id", type=int)
    show.add_argument("--material", type=int, help="check it against this material's particles")
    create = leaf(rsub, "create", rig_create, "create a rig from a JSON record (as POST /rigs)", creates=True)
    create.add_argument("file", help="JSON record, '-' for stdin")
    create.add_argument("--name", help="the rig's name (replaces the file's)")
    create.add_argument("--material", type=int, help="check it against this material's particles")


__all__ = ["register"]
