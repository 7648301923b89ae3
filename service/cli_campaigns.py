"""``demcal material|campaign|schedule ...``: every calibration action, scripted through the HTTP API.

The commands talk to a running service (``--url``, else $DEMCAL_URL, else $DEMCAL_HOST/$DEMCAL_PORT:
service.cli_http.service_url) with httpx, so they work against a remote service as
well as a local one. Any error (HTTP 4xx/5xx, no server, bad input file) is a
one-line message on stderr and exit status 2, never a traceback.
"""
from __future__ import annotations

from types import SimpleNamespace

from calibration.awaiting import awaited
from calibration.evaluator_registry import names as evaluator_names
from calibration.vocabulary import Phase, PolishStage
from service import cli_export
from service.cli_http import CliError, bar, watch, watch_options
from service.cli_http import call as _call
from service.cli_http import emit as _emit
from service.cli_http import fmt as _fmt
from service.cli_http import leaf as _leaf
from service.cli_http import pairs as _pairs
from service.cli_http import read_json as _read_json
from service.cli_http import page_footer, page_options, page_params
from service.cli_http import table as _table
from service.cli_resolution import estimate_line, resolution_body, resolution_options
from service.vocabulary import CampaignStatus, RunStatus



# -- materials -------------------------------------------------------------------------------------

def material_list(args) -> int:
    data = _call(args, "GET", "/materials", params=page_params(args))
    return _emit(args, data, _table(["id", "name", "measurements", "bundled", "owner"],
                                    [[m["id"], m["name"], len(m["measurements"]), m["bundled"], m.get("owner")]
                                     for m in data["items"]]) + page_footer(data))


def material_show(args) -> int:
    m = _call(args, "GET", f"/materials/{args.id}")
    rows = [[x["id"], x["test"], x["quantity"], x["condition"], x["n"], x["mean"], x["standard_uncertainty"], x["unit"]]
            for x in m["measurements"]]
    text = f"{m['name']} (#{m['id']})\n{m['description']}\n\n" + _table(
        ["id", "test", "quantity", "condition", "n", "mean", "std.unc.", "unit"], rows)
    return _emit(args, m, text)


def material_add(args) -> int:
    from service.materials.replicates import ReplicateError, parse_replicates  # the package imports the store

    try:
        values = parse_replicates(args.values, "--values")
    except ReplicateError as exc:
        raise CliError(str(exc)) from exc
    body = {"test": args.test, "quantity": args.quantity, "values": values, "source": args.source or "",
            "condition": _pairs(args.condition, "--condition"), "condition_units": _pairs(args.condition_unit,
                                                                                             "--condition-unit", str)}
    if args.unit:
        body["unit"] = args.unit
    m = _call(args, "POST", f"/materials/{args.id}/measurements", body)
    # the count shows how the list was read (a decimal comma is one value, not two)
    return _emit(args, m, f"measurement {m['id']}: {m['test']}/{m['quantity']}, {len(values)} replicate(s), "
                          f"mean {_fmt(m['mean'])} {m['unit']}")


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
                "polish_steps", "polish_when", "polish_jacobian"):
        value = getattr(args, key)
        if value is not None:
            body[key] = value
    if args.automatic:
        body["automatic"] = True
    if args.diagnose_always:
        body["diagnose_always"] = True
    if args.no_reuse:
        body["reuse"] = False
    if args.all_seeds:
        body["adaptive_replicates"] = False
    if args.no_holdout:
        body["polish_holdout"] = False
    if args.factor:
        body["factors"] = [_factor(f) for f in args.factor]
    if args.centre_runs is not None or args.generators:
        design = body.setdefault("design", {})
        if args.centre_runs is not None:
            design["centre_runs"] = args.centre_runs
        if args.generators:
            design.update(type="fractional", generators=args.generators)
    resolution = resolution_body(args)
    if resolution is not None:
        body["resolution"] = resolution
    c = _call(args, "POST", "/campaigns", body)
    estimate = estimate_line(c.get("estimate"))
    if args.start:
        c = _call(args, "POST", f"/campaigns/{c['id']}/start")
    return _emit(args, c, f"campaign {c['id']} {c['status']}" + (f"\n{estimate}" if estimate else ""))


# What each phase that waits for batteries waits for, by name; the count is the phase's own (the loop's
# rule, calibration.awaiting.awaited), known when the phase starts, so it does not grow as phases are added.
PHASE_RUNS = {Phase.BATTERIES: "design runs", Phase.CONFIRMATION: "confirmation seeds",
              Phase.POLISH: "polish round", Phase.DIAGNOSIS: "diagnosis batteries"}


def _phase_progress(args, c: dict) -> str:
    """``design runs [#####.....] 5/11`` for a running campaign's current phase, else what it is doing."""
    if c["status"] != CampaignStatus.RUNNING:
        return f"phase {c['phase'] or '-'}, runs {c['runs_succeeded']}/{c['runs_total']}"
    if c["phase"] in (None, Phase.DONE):  # the runner has yet to make the (next) iteration
        return f"starting iteration {c['current_iteration'] + 1}"
    base = f"/campaigns/{c['id']}"
    # the polishing's state before the runs: a round's runs are stored with the state that starts it, so
    # the runs read after it include the state's round
    optimum = (_call(args, "GET", f"{base}/optimum", params={"number": c["current_iteration"]})
               if c["phase"] == Phase.POLISH else None)
    it = _call(args, "GET", f"{base}/iterations/{c['current_iteration']}")
    phase = it["phase"]  # the iteration's own, read with its runs
    view = SimpleNamespace(phase=phase, optimum=optimum, runs=[SimpleNamespace(**r) for r in it["runs"]])
    runs = awaited(view) if phase in PHASE_RUNS else []
    if not runs:  # a computation, or a phase changing between the reads
        return f"phase {phase}" + ("" if phase == Phase.DONE else " (computing)")
    done = sum(r.status == RunStatus.SUCCEEDED for r in runs)
    failed = sum(r.status in (RunStatus.FAILED, RunStatus.CANCELLED) for r in runs)
    label = PHASE_RUNS[Phase(phase)]
    if phase == Phase.POLISH:
        state = (optimum or {}).get("polish") or {}
        label = ("held-out confirmation" if state.get("stage") == PolishStage.HOLDOUT
                 else f"{label} {state.get('round', '')}".rstrip())
    return f"phase {phase}: {label} {bar(done, len(runs))}" + (f", {failed} failed" if failed else "")


def _status_text(c: dict, progress: str | None = None) -> str:
    progress = progress or f"phase {c['phase'] or '-'}, runs {c['runs_succeeded']}/{c['runs_total']}"
    text = f"campaign {c['id']} {c['name']!r}: {c['status']}, iteration {c['current_iteration']}, {progress}"
    if c.get("stop_reason"):
        text += f"\nautomatic mode stopped: {c['stop_reason']}"
    if c.get("kept_iteration") is not None:
        text += f"\nthe model kept is iteration {c['kept_iteration']}'s"
    if c.get("continuable"):
        text += f"\nmore iterations could go on from here: demcal campaign continue {c['id']}"
    return text + (f"\nerror: {c['error']}" if c.get("error") else "")


def campaign_list(args) -> int:
    data = _call(args, "GET", "/campaigns", params=page_params(args, status=args.status))
    return _emit(args, data, _table(["id", "name", "material", "status", "iteration", "phase", "owner"],
                                    [[c["id"], c["name"], c["material_id"], c["status"], c["current_iteration"],
                                      c["phase"], c.get("owner")] for c in data["items"]]) + page_footer(data))


def campaign_action(args) -> int:
    c = _call(args, "POST", f"/campaigns/{args.id}/{args.action}")
    return _emit(args, c, _status_text(c))


def campaign_status(args) -> int:
    """A campaign's state with its phase's progress; --watch follows it until it stops running (exit
    status 0 when it completed, 1 when it failed or was paused)."""
    def fetch() -> dict:
        return _call(args, "GET", f"/campaigns/{args.id}")

    def render(c: dict) -> str:
        return _status_text(c, _phase_progress(args, c))

    if not args.watch:
        c = fetch()
        return _emit(args, c, render(c))
    if args.json:
        raise CliError("--watch draws progress for people; poll without it for --json")
    c = watch(args, fetch, render, lambda c: c["status"] != CampaignStatus.RUNNING)
    return 0 if c["status"] == CampaignStatus.COMPLETED else 1


def _strength(row: dict, diagnosis: dict) -> str:
    """The estimated strength in its unit (the candidate's, as GET /effects gives it), or a switch-type
    effect's share of its full switch; "none (opposite sign)" or "none (unseen)" where no strength can be
    read (``calibration.attribute.strength_reading``: the page and the HTML report say the same)."""
    from calibration.attribute import strength_reading

    value = strength_reading(row, diagnosis)
    if value is None:
        return "-"
    if isinstance(value, str):
        return f"none ({value})"
    if row["strength"] is None:
        return f"{100 * value:.3g} % of the switch"
    unit = row.get("unit")
    return _fmt(value) + ("" if unit in (None, "", "1") else f" {unit}")


def campaign_diagnosis(args) -> int:
    params = {"number": args.iteration} if args.iteration else None
    d = _call(args, "GET", f"/campaigns/{args.id}/diagnosis", params=params)
    rows = [[r["effect"], r["title"], r["lm"], r["p_holm"], r["explained"], _strength(r, d),
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
    rows = [[e["number"], (", ".join(e["effects"]) or "-") + (" (range widened)" if e.get("range_widened") else "")
             + (f" (box widened: {', '.join(e['box_widened'])})" if e.get("box_widened") else ""),
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
    if args.override:
        body["override"] = True
    resolution = resolution_body(args)
    if resolution is not None:
        body["resolution"] = resolution
    total = _call(args, "GET", f"/campaigns/{args.id}/iterations", params={"limit": 1})["total"]
    last = (_call(args, "GET", f"/campaigns/{args.id}/iterations", params={"limit": 1, "offset": total - 1})["items"][0]
            if total else None)
    c = _call(args, "POST", f"/campaigns/{args.id}/iterations", body=body)
    return _emit(args, c, _next_text(c, last, args.add_effect))


def campaign_continue(args) -> int:
    """A completed automatic campaign taken up again: its last iteration's next step decided again under the
    raised limit, and what the loop had stopped for."""
    c = _call(args, "POST", f"/campaigns/{args.id}/continue", body={"more_iterations": args.iterations})
    total = _call(args, "GET", f"/campaigns/{args.id}/iterations", params={"limit": 1})["total"]
    last = _call(args, "GET", f"/campaigns/{args.id}/iterations", params={"limit": 1, "offset": total - 1})["items"][0]
    record = (last.get("report") or {}).get("automatic") or {}
    continued = record.get("continued") or {}
    text = (f"campaign {c['id']} continues after iteration {last['number']} (limit now {continued.get('max_iterations')}; "
            f"it had stopped: {continued.get('stopped_for')}): iteration {last['number'] + 1} "
            + (f"adds {record['next_effect']}" if record.get("next_effect") else "runs the same model in a wider box")
            + (f", fitted in place of {record['alias_refit']['leader']}" if record.get("alias_refit") else ""))
    return _emit(args, c, text)


def _next_text(c: dict, last: dict | None, effect: str | None) -> str:
    """What the iteration just asked for will run (the campaign's summary still shows the finished one
    until the runner makes the new one): its number, the effect and factors it adds or changes."""
    number = (last["number"] if last else 0) + 1
    old = {f["name"]: f for f in ((last or {}).get("parameters") or {}).get("factors", [])}
    new = c["config"].get("factors", [])

    def span(f: dict) -> str:
        return f"{f['name']} {_fmt(float(f['low']))}..{_fmt(float(f['high']))}"

    added = [span(f) for f in new if f["name"] not in old]
    changed = [span(f) for f in new if f["name"] in old
               and (old[f["name"]]["low"], old[f["name"]]["high"]) != (f["low"], f["high"])]
    dropped = sorted(set(old) - {f["name"] for f in new})
    text = f"campaign {c['id']}: iteration {number} {c['status']}"
    if effect:
        text += f", with {effect} added"
    for what, names in (("new factor", added), ("new range", changed), ("dropped factor", dropped)):
        if names:
            text += f"\n{what}{'s' if len(names) > 1 else ''}: " + "; ".join(names)
    return text + f"\nfactors ({len(new)}): " + ", ".join(f["name"] for f in new)


def _anchor(anchor: dict) -> str:
    """One line of a polish's anchor: what was held, its batteries' chi2, whether the steps started there, and
    the step tried from it (calibration.polish._anchor_steps)."""
    held = ", ".join(f"{name} {_fmt(value)}" for name, value in anchor["held"].items())
    line = (f"held at the measured {held}: chi2 {_fmt(anchor.get('chi2'))}, "
            + ("the batteries preferred it and the steps started there" if anchor.get("taken") else "not better"))
    if anchor.get("step_chi2") is not None:
        line += (f"; one step from it: chi2 {_fmt(anchor['step_chi2'])}, "
                 + ("the best trial, the polish went on from there" if anchor.get("step_taken") else "not taken"))
    return line


def _intervals(intervals: dict | None) -> str:
    """The report's parameters with their intervals (calibration.intervals): one row each, with a cut at the box or a
    widening by points measured on the batteries noted; then each pair that trades, as the page shows them."""
    if not intervals or not intervals.get("parameters"):
        return ""
    widened = set((intervals.get("measured_points") or {}).get("widened") or [])
    rows = []
    for name, p in intervals["parameters"].items():
        notes = [f"cut at the box ({', '.join(p['at_bound'])})"] if p.get("at_bound") else []
        if name in widened and p.get("wald"):
            notes.append(f"widened to the points measured on the batteries (the surfaces' alone: "
                         f"[{_fmt(p['wald']['low'])}, {_fmt(p['wald']['high'])}])")
        rows.append([name, p["value"], "not identified" if p.get("sd") is None else p["sd"],
                     "-" if p.get("low") is None else f"[{_fmt(p['low'])}, {_fmt(p['high'])}]", "; ".join(notes) or "-"])
    text = f"\n\nparameters, {_fmt(100 * intervals['level'])} % intervals:\n" + _table(
        ["parameter", "optimum", "sd", "interval", "note"], rows)
    if intervals.get("scaled_by_misfit"):
        text += (f"\nintervals widened by chi2/dof {_fmt(intervals['scale'])}: the model misses the measurements by "
                 "more than their noise")
    return text + "".join(f"\ntrade: {t['message']}" for t in intervals.get("trades") or [])


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
                      for row in rows])
            + _intervals(r.get("intervals")))
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
            f"chi2 {_fmt(polished['chi2_start'])} -> {_fmt(polished['chi2'])}, Jacobian from the "
            f"{polished.get('jacobian') or 'batteries'}" + (f"; why: {polished['why']}" if polished.get("why") else "")
            + (f"\n  held out: the chosen point again at {len(polished['holdout_seeds'])} fresh seed(s), chi2 "
               f"{_fmt(polished.get('holdout_chi2'))}; the report reads these batteries"
               if polished.get("holdout_seeds") else "")
            + "".join(f"\n  {_anchor(a)}" for a in polished.get("anchors") or [])))
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
    data = _call(args, "GET", "/schedules", params=page_params(args))
    return _emit(args, data, _table(["id", "name", "cron", "enabled", "only new data", "next run", "last campaign",
                                     "owner"],
                                    [[s["id"], s["name"], s["cron"], s["enabled"], s["only_if_new_measurements"],
                                      s["next_run_at"], s["last_campaign_id"], s.get("owner")] for s in data["items"]])
                 + page_footer(data))


def schedule_delete(args) -> int:
    _call(args, "DELETE", f"/schedules/{args.id}")
    return _emit(args, {"deleted": args.id}, f"schedule {args.id} deleted")


# -- wiring ----------------------------------------------------------------------------------------

def register(subparsers) -> None:
    material = subparsers.add_parser("material", help="materials and their measurements")
    msub = material.add_subparsers(dest="material_command", required=True)
    page_options(_leaf(msub, "list", material_list, "list materials (a page; the total below)"))
    _leaf(msub, "show", material_show, "show a material's measurements (SI)").add_argument("id", type=int)
    mcreate = _leaf(msub, "create", material_create, "create a material from a JSON body (as POST /materials) "
                    "and/or flags", creates=True)
    mcreate.add_argument("--file", help="JSON body, '-' for stdin")
    mcreate.add_argument("--name")
    mcreate.add_argument("--description")
    mcreate.add_argument("--source")
    _leaf(msub, "delete", material_delete, "delete a material no campaign uses").add_argument("id", type=int)
    dm = _leaf(msub, "delete-measurement", material_delete_measurement, "delete one measurement of a material")
    dm.add_argument("id", type=int)
    dm.add_argument("measurement", type=int)
    cp = _leaf(msub, "copy", material_copy, "copy a material (e.g. the read-only bundled one) to edit it",
               creates=True)
    cp.add_argument("id", type=int)
    cp.add_argument("--name", required=True, help="name of the copy")
    add = _leaf(msub, "add-measurement", material_add, "add replicate values of one measurement", creates=True)
    add.add_argument("id", type=int)
    add.add_argument("--test", required=True)
    add.add_argument("--quantity", required=True)
    add.add_argument("--values", required=True,
                     help="replicate values separated by ';', spaces or new lines, e.g. '1412; 1383.6; 1397.8'; a "
                          "decimal comma is read where unambiguous ('1397,8'), else refused ('1,397')")
    add.add_argument("--unit", help="unit of the values, e.g. kPa (default SI)")
    add.add_argument("--condition", action="append", help="NAME=VALUE, e.g. normal_stress_pa=24 (repeatable)")
    add.add_argument("--condition-unit", action="append", help="NAME=UNIT, e.g. normal_stress_pa=kPa")
    add.add_argument("--source")
    cli_export.register_material(msub)

    campaign = subparsers.add_parser("campaign", help="calibration campaigns")
    csub = campaign.add_subparsers(dest="campaign_command", required=True)
    create = _leaf(csub, "create", campaign_create, "create a campaign from a JSON file and/or flags", creates=True)
    create.add_argument("--file", help="JSON body (as POST /campaigns), '-' for stdin")
    create.add_argument("--name")
    create.add_argument("--material", dest="material_id", type=int)
    create.add_argument("--evaluator", choices=evaluator_names())
    create.add_argument("--fidelity", choices=["screening", "thesis"])
    resolution_options(create)
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
                        help="polish every iteration, or (default) only one whose confirmation the response "
                             "surfaces did not predict or whose added effect misses there")
    create.add_argument("--polish-jacobian", choices=["surfaces", "batteries"],
                        help="the polishing's first Jacobian: the surfaces' slopes (default) or forward differences "
                             "on the batteries (one point per factor and seed)")
    create.add_argument("--no-holdout", action="store_true",
                        help="after a polish that took a step, let the report read the polish's own batteries "
                             "instead of the chosen point run again at fresh seeds (which costs one battery per "
                             "confirmation seed: the steps chose on their batteries, which then flatter the fit)")
    create.add_argument("--no-reuse", action="store_true",
                        help="run every design point of a later iteration, even where an earlier one ran it")
    create.add_argument("--all-seeds", action="store_true",
                        help="run the diagnosis at every confirmation seed at once, not one seed first")
    create.add_argument("--start", action="store_true", help="start it right away")
    list_parser = _leaf(csub, "list", campaign_list, "list campaigns, newest first (a page; the total below)")
    page_options(list_parser)
    list_parser.add_argument("--status", choices=CampaignStatus.values())
    for action, text in (("start", "start a draft campaign"), ("pause", "pause a running campaign"),
                         ("resume", "resume a paused campaign"),
                         ("retry", "run a failed campaign on: its failed batteries queued again, the others kept")):
        _leaf(csub, action, campaign_action, text).add_argument("id", type=int)
        csub.choices[action].set_defaults(action=action)
    status = _leaf(csub, "status", campaign_status, "a campaign's state and its phase's progress")
    status.add_argument("id", type=int)
    watch_options(status, "it completes, fails or is paused (exit status 0 when it completed, else 1)")
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
    nxt.add_argument("--override", action="store_true",
                     help="add the effect although the last diagnosis found no physical match or a suspect measurement")
    nxt.add_argument("--proposed-design", action="store_true",
                     help="run the design the surface check proposed (narrowed factorial or axial runs)")
    resolution_options(nxt)  # e.g. a coarse factor nearer 1, or as_measured to confirm at the particles' own size
    more = _leaf(csub, "continue", campaign_continue, "take a completed automatic campaign up again with more "
                 "iterations (refused when it stopped for a reason more iterations do not change)")
    more.add_argument("id", type=int)
    more.add_argument("--iterations", type=int, default=1, help="iterations beyond the last one (default 1)")
    cli_export.register_campaign(csub)

    schedule = subparsers.add_parser("schedule", help="cron schedules that start campaigns")
    ssub = schedule.add_subparsers(dest="schedule_command", required=True)
    screate = _leaf(ssub, "create", schedule_create, "create a schedule (cron in UTC)")
    screate.add_argument("--name", required=True)
    screate.add_argument("--cron", required=True, help="5 fields, e.g. '0 2 * * *', or @daily")
    screate.add_argument("--campaign-file", help="campaign template JSON (as POST /campaigns)")
    screate.add_argument("--from-campaign", type=int, help="reuse an existing campaign's configuration")
    screate.add_argument("--only-new", action="store_true", help="only when new measurements arrived")
    screate.add_argument("--policy", choices=["coalesce", "skip"], default="coalesce", help="missed-run policy")
    page_options(_leaf(ssub, "list", schedule_list, "list schedules (a page; the total below)"))
    _leaf(ssub, "delete", schedule_delete, "delete a schedule").add_argument("id", type=int)
