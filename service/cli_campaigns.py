"""``demcal material|campaign|schedule ...``: every calibration action, scripted through the HTTP API.

The commands talk to a running service (``--url``, default $DEMCAL_URL or
http://127.0.0.1:8000) with httpx, so they work against a remote service as
well as a local one. Any error (HTTP 4xx/5xx, no server, bad input file) is a
one-line message on stderr and exit status 2, never a traceback.
"""
from __future__ import annotations

from calibration.evaluator_registry import names as evaluator_names
from service.cli_http import CliError
from service.cli_http import call as _call
from service.cli_http import emit as _emit
from service.cli_http import fmt as _fmt
from service.cli_http import leaf as _leaf
from service.cli_http import pairs as _pairs
from service.cli_http import read_json as _read_json
from service.cli_http import table as _table
from service.vocabulary import CampaignStatus



# -- materials -------------------------------------------------------------------------------------

def material_list(args) -> int:
    data = _call(args, "GET", "/materials")
    return _emit(args, data, _table(["id", "name", "measurements", "bundled"],
                                    [[m["id"], m["name"], len(m["measurements"]), m["bundled"]] for m in data]))


def material_show(args) -> int:
    m = _call(args, "GET", f"/materials/{args.id}")
    rows = [[x["id"], x["test"], x["quantity"], x["condition"], x["n"], x["mean"], x["standard_uncertainty"], x["unit"]]
            for x in m["measurements"]]
    text = f"{m['name']} (#{m['id']})\n{m['description']}\n\n" + _table(
        ["id", "test", "quantity", "condition", "n", "mean", "std.unc.", "unit"], rows)
    return _emit(args, m, text)


def material_add(args) -> int:
    try:
        values = [float(v) for v in args.values.split(",")]
    except ValueError as exc:
        raise CliError(f"--values: {exc}") from exc
    body = {"test": args.test, "quantity": args.quantity, "values": values, "source": args.source or "",
            "condition": _pairs(args.condition, "--condition"), "condition_units": _pairs(args.condition_unit,
                                                                                             "--condition-unit", str)}
    if args.unit:
        body["unit"] = args.unit
    m = _call(args, "POST", f"/materials/{args.id}/measurements", body)
    return _emit(args, m, f"measurement {m['id']}: {m['test']}/{m['quantity']} mean {_fmt(m['mean'])} {m['unit']}")


def material_create(args) -> int:
    body = _read_json(args.file) if args.file else {}
    for key in ("name", "description", "source"):
        value = getattr(args, key)
        if value is not None:
            body[key] = value
    m = _call(args, "POST", "/materials", body)
    return _emit(args, m, f"material {m['id']}: {m['name']} ({len(m['measurements'])} measurements)")


def material_delete(args) -> int:
    _call(args, "DELETE", f"/materials/{args.id}")
    return _emit(args, {"deleted": args.id}, f"material {args.id} deleted")


def material_delete_measurement(args) -> int:
    _call(args, "DELETE", f"/materials/{args.id}/measurements/{args.measurement}")
    return _emit(args, {"deleted": args.measurement}, f"measurement {args.measurement} of material {args.id} deleted")


def material_copy(args) -> int:
    m = _call(args, "POST", f"/materials/{args.id}/copy", {"name": args.name})
    return _emit(args, m, f"material {m['id']}: {m['name']} (copy of #{args.id}, {len(m['measurements'])} measurements)")


# -- campaigns -------------------------------------------------------------------------------------

def _factor(text: str) -> dict:
    parts = text.split(":")
    if len(parts) != 3:
        raise CliError(f"--factor {text!r}: expected NAME:LOW:HIGH")
    try:
        return {"name": parts[0], "low": float(parts[1]), "high": float(parts[2])}
    except ValueError as exc:
        raise CliError(f"--factor {text!r}: {exc}") from exc


def campaign_create(args) -> int:
    body = _read_json(args.file) if args.file else {}
    for key in ("name", "material_id", "evaluator", "fidelity", "seed", "max_iterations", "confirmation_seeds",
                "polish_steps", "polish_when"):
        value = getattr(args, key)
        if value is not None:
            body[key] = value
    if args.automatic:
        body["automatic"] = True
    if args.diagnose_always:
        body["diagnose_always"] = True
    if args.factor:
        body["factors"] = [_factor(f) for f in args.factor]
    if args.centre_runs is not None or args.generators:
        design = body.setdefault("design", {})
        if args.centre_runs is not None:
            design["centre_runs"] = args.centre_runs
        if args.generators:
            design.update(type="fractional", generators=args.generators)
    c = _call(args, "POST", "/campaigns", body)
    if args.start:
        c = _call(args, "POST", f"/campaigns/{c['id']}/start")
    return _emit(args, c, f"campaign {c['id']} {c['status']}")


def _status_text(c: dict) -> str:
    text = (f"campaign {c['id']} {c['name']!r}: {c['status']}, iteration {c['current_iteration']}, "
            f"phase {c['phase'] or '-'}, runs {c['runs_succeeded']}/{c['runs_total']}")
    if c.get("stop_reason"):
        text += f"\nautomatic mode stopped: {c['stop_reason']}"
    return text + (f"\nerror: {c['error']}" if c.get("error") else "")


def campaign_list(args) -> int:
    data = _call(args, "GET", "/campaigns", params={"status": args.status} if args.status else None)
    return _emit(args, data, _table(["id", "name", "material", "status", "iteration", "phase"],
                                    [[c["id"], c["name"], c["material_id"], c["status"], c["current_iteration"],
                                      c["phase"]] for c in data]))


def campaign_action(args) -> int:
    method = "GET" if args.action == "status" else "POST"
    path = f"/campaigns/{args.id}" + ("" if args.action == "status" else f"/{args.action}")
    c = _call(args, method, path)
    return _emit(args, c, _status_text(c))


def campaign_diagnosis(args) -> int:
    params = {"number": args.iteration} if args.iteration else None
    d = _call(args, "GET", f"/campaigns/{args.id}/diagnosis", params=params)
    rows = [[r["effect"], r["title"], r["lm"], r["p_holm"], r["explained"],
             r["strength"] if r["strength"] is not None else r.get("fraction_of_switch"),
             "yes" if r["plausible"] else "no", r["alias_group"] or ""] for r in d["ranking"]]
    text = (f"campaign {d['campaign_id']} iteration {d['iteration']}: {d['verdict']}\n{d['message']}\n\n"
            + _table(["effect", "physics", "LM", "Holm p", "explained", "strength", "plausible", "alias group"],
                     [[_fmt(c) if isinstance(c, float) else c for c in row] for row in rows]))
    for g in d.get("alias_groups", []):
        text += f"\nalias group {g['group']}: {', '.join(g['effects'])}: {g['message']}"
    if d.get("measure_next"):
        text += "\nmeasure next: " + "; ".join(d["measure_next"])
    return _emit(args, d, text)


def campaign_history(args) -> int:
    h = _call(args, "GET", f"/campaigns/{args.id}/history")
    rows = [[e["number"], (", ".join(e["effects"]) or "-") + (" (range widened)" if e.get("range_widened") else ""),
             e["chi2_per_dof"],
             "[" + ", ".join(_fmt(x) for x in e["noise_band"] or []) + "]", e["verdict"],
             ", ".join(e.get("effect_added_next") or []) or "-"] for e in h["iterations"]]
    return _emit(args, h, _table(["iteration", "effects", "chi2/dof", "noise band", "verdict", "added next"],
                                 [[_fmt(c) if isinstance(c, float) else c for c in row] for row in rows]))


def campaign_next(args) -> int:
    body = {}
    if args.add_effect:
        body["add_effect"] = args.add_effect
    if args.strength_range:
        try:
            body["strength_range"] = [float(x) for x in args.strength_range.split(":")]
        except ValueError as exc:
            raise CliError(f"--strength-range {args.strength_range!r}: expected LOW:HIGH ({exc})") from exc
    if args.proposed_design:
        body["proposed_design"] = True
    c = _call(args, "POST", f"/campaigns/{args.id}/iterations", body=body)
    return _emit(args, c, _status_text(c))


def campaign_report(args) -> int:
    params = {"number": args.iteration} if args.iteration else None
    r = _call(args, "GET", f"/campaigns/{args.id}/report", params=params)
    rows = [[t["test"], t["quantity"], t["condition"], t["measured"], t.get("measured_uncertainty"),
             t.get("predicted"), t.get("prediction_interval"), t.get("confirmed"), t.get("standardised_residual"),
             t.get("reachability"), t["status"]] for t in r["targets"]]
    text = (f"campaign {r['campaign_id']} iteration {r['iteration']}: {r['verdict']}\n"
            f"optimum: {_fmt(r['optimum'])}\n\n"
            + _table(["test", "quantity", "condition", "measured", "u", "predicted", "95% PI", "confirmed", "z",
                      "min|z| in box", "status"],
                     [[c if not isinstance(c, list) else "[" + ", ".join(_fmt(x) for x in c) + "]" for c in row]
                      for row in rows]))
    if r.get("meaning"):
        text += f"\n\n{r['verdict']}: {r['meaning']}"
    lof = r.get("lack_of_fit")
    if lof:
        text += (f"\nlack of fit: chi2 {_fmt(lof['statistic'])} on {lof['dof']} dof "
                 f"(per dof {_fmt(lof['chi2_per_dof'])}, "
                 f"noise band [{_fmt(lof['noise_band'][0])}, {_fmt(lof['noise_band'][1])}]), p {_fmt(lof['p_value'])}")
    adequacy = r.get("adequacy")
    if adequacy:
        text += (f"\nwith the candidate effects' directed test: p {_fmt((adequacy.get('directed') or {}).get('p_value'))}; "
                 f"with the lack of fit (Holm) p {_fmt(adequacy['p_value'])}: "
                 + ("the model misses the measurements" if adequacy["fails"] else "no misfit beyond noise"))
    for b in (r.get("conflicts") or {}).get("active_bounds", []):
        text += f"\nat a bound: {b['parameter']} at its {b['side']} end, pushing {b['pushes']}"
    for p in (r.get("conflicts") or {}).get("priors_pulled", []):
        text += f"\nprior conflict: {p['meaning']}"
    if r.get("surrogate_check"):
        text += (f"\nresponse surfaces at the optimum: {r['surrogate_check'].get('verdict')}: "
                 f"{r['surrogate_check'].get('reason')}")
    polished = r.get("polish")
    if polished:
        text += ("\npolishing on the batteries: " + (
            f"skipped, the surfaces predicted the confirmation ({polished['skipped']})" if polished.get("skipped") else
            f"{polished['steps']} Gauss-Newton step(s), {polished['batteries']} batteries, "
            f"chi2 {_fmt(polished['chi2_start'])} -> {_fmt(polished['chi2'])}"))
    return _emit(args, r, text)


# -- schedules -------------------------------------------------------------------------------------

def schedule_create(args) -> int:
    if bool(args.campaign_file) == bool(args.from_campaign):
        raise CliError("give exactly one of --campaign-file or --from-campaign")
    template = (_read_json(args.campaign_file) if args.campaign_file
                else _call(args, "GET", f"/campaigns/{args.from_campaign}")["config"])
    body = {"name": args.name, "cron": args.cron, "template": template,
            "only_if_new_measurements": args.only_new, "missed_run_policy": args.policy}
    s = _call(args, "POST", "/schedules", body)
    return _emit(args, s, f"schedule {s['id']} {s['cron']!r}: next run {s['next_run_at']}")


def schedule_list(args) -> int:
    data = _call(args, "GET", "/schedules")
    return _emit(args, data, _table(["id", "name", "cron", "enabled", "only new data", "next run", "last campaign"],
                                    [[s["id"], s["name"], s["cron"], s["enabled"], s["only_if_new_measurements"],
                                      s["next_run_at"], s["last_campaign_id"]] for s in data]))


def schedule_delete(args) -> int:
    _call(args, "DELETE", f"/schedules/{args.id}")
    return _emit(args, {"deleted": args.id}, f"schedule {args.id} deleted")


# -- wiring ----------------------------------------------------------------------------------------

def register(subparsers) -> None:
    material = subparsers.add_parser("material", help="materials and their measurements")
    msub = material.add_subparsers(dest="material_command", required=True)
    _leaf(msub, "list", material_list, "list materials")
    _leaf(msub, "show", material_show, "show a material's measurements (SI)").add_argument("id", type=int)
    mcreate = _leaf(msub, "create", material_create, "create a material from a JSON body (as POST /materials) "
                    "and/or flags")
    mcreate.add_argument("--file", help="JSON body, '-' for stdin")
    mcreate.add_argument("--name")
    mcreate.add_argument("--description")
    mcreate.add_argument("--source")
    _leaf(msub, "delete", material_delete, "delete a material no campaign uses").add_argument("id", type=int)
    dm = _leaf(msub, "delete-measurement", material_delete_measurement, "delete one measurement of a material")
    dm.add_argument("id", type=int)
    dm.add_argument("measurement", type=int)
    cp = _leaf(msub, "copy", material_copy, "copy a material (e.g. the read-only bundled one) to edit it")
    cp.add_argument("id", type=int)
    cp.add_argument("--name", required=True, help="name of the copy")
    add = _leaf(msub, "add-measurement", material_add, "add replicate values of one measurement")
    add.add_argument("id", type=int)
    add.add_argument("--test", required=True)
    add.add_argument("--quantity", required=True)
    add.add_argument("--values", required=True, help="comma-separated replicate values")
    add.add_argument("--unit", help="unit of the values, e.g. kPa (default SI)")
    add.add_argument("--condition", action="append", help="NAME=VALUE, e.g. normal_stress_pa=24 (repeatable)")
    add.add_argument("--condition-unit", action="append", help="NAME=UNIT, e.g. normal_stress_pa=kPa")
    add.add_argument("--source")

    campaign = subparsers.add_parser("campaign", help="calibration campaigns")
    csub = campaign.add_subparsers(dest="campaign_command", required=True)
    create = _leaf(csub, "create", campaign_create, "create a campaign from a JSON file and/or flags")
    create.add_argument("--file", help="JSON body (as POST /campaigns), '-' for stdin")
    create.add_argument("--name")
    create.add_argument("--material", dest="material_id", type=int)
    create.add_argument("--evaluator", choices=evaluator_names())
    create.add_argument("--fidelity", choices=["screening", "thesis"])
    create.add_argument("--factor", action="append", help="NAME:LOW:HIGH in SI (repeatable)")
    create.add_argument("--centre-runs", type=int)
    create.add_argument("--generators", nargs="+", help="e.g. D=ABC (makes the design fractional)")
    create.add_argument("--seed", type=int)
    create.add_argument("--automatic", action="store_true",
                        help="add the indicated effects and iterate by itself until the lack of fit passes, "
                             "nothing improves, or --max-iterations")
    create.add_argument("--diagnose-always", action="store_true",
                        help="diagnose after every report, also a passing one: the directed test over the candidate "
                             "effects sees misfit the lack of fit misses (a baseline and one battery per candidate, per seed)")
    create.add_argument("--max-iterations", type=int, help="automatic mode: iterations at most (default 4)")
    create.add_argument("--confirmation-seeds", type=int,
                        help="batteries at each optimum, one per seed (default 2); the report uses their mean")
    create.add_argument("--polish-steps", type=int,
                        help="Gauss-Newton steps on the batteries after the confirmation (default 3; 0: none)")
    create.add_argument("--polish-when", choices=["always", "surrogate_misses"],
                        help="polish every iteration (default), or only one whose confirmation the response "
                             "surfaces did not predict")
    create.add_argument("--start", action="store_true", help="start it right away")
    list_parser = _leaf(csub, "list", campaign_list, "list campaigns")
    list_parser.add_argument("--status", choices=CampaignStatus.values())
    for action, text in (("start", "start a draft campaign"), ("pause", "pause a running campaign"),
                         ("resume", "resume a paused campaign"), ("status", "show a campaign's state")):
        _leaf(csub, action, campaign_action, text).add_argument("id", type=int)
        csub.choices[action].set_defaults(action=action)
    report = _leaf(csub, "report", campaign_report, "measured vs predicted vs confirmed per target")
    report.add_argument("id", type=int)
    report.add_argument("--iteration", type=int)
    diag = _leaf(csub, "diagnosis", campaign_diagnosis, "which effect is missing: ranking, alias groups",
                 aliases=("diagnose",))
    diag.add_argument("id", type=int)
    diag.add_argument("--iteration", type=int)
    _leaf(csub, "history", campaign_history, "weighted error per iteration and the effect added").add_argument(
        "id", type=int)
    nxt = _leaf(csub, "next", campaign_next, "start the next iteration, e.g. with an effect added as a factor",
                aliases=("iterate",))
    nxt.add_argument("id", type=int)
    nxt.add_argument("--add-effect", help="a candidate from GET /api/v1/effects, e.g. rolling_epsd2")
    nxt.add_argument("--strength-range", help="LOW:HIGH of the added effect's strength (SI)")
    nxt.add_argument("--proposed-design", action="store_true",
                     help="run the design the surface check proposed (narrowed factorial or axial runs)")

    schedule = subparsers.add_parser("schedule", help="cron schedules that start campaigns")
    ssub = schedule.add_subparsers(dest="schedule_command", required=True)
    screate = _leaf(ssub, "create", schedule_create, "create a schedule (cron in UTC)")
    screate.add_argument("--name", required=True)
    screate.add_argument("--cron", required=True, help="5 fields, e.g. '0 2 * * *', or @daily")
    screate.add_argument("--campaign-file", help="campaign template JSON (as POST /campaigns)")
    screate.add_argument("--from-campaign", type=int, help="reuse an existing campaign's configuration")
    screate.add_argument("--only-new", action="store_true", help="only when new measurements arrived")
    screate.add_argument("--policy", choices=["coalesce", "skip"], default="coalesce", help="missed-run policy")
    _leaf(ssub, "list", schedule_list, "list schedules")
    _leaf(ssub, "delete", schedule_delete, "delete a schedule").add_argument("id", type=int)
