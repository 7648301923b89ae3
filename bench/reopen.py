"""A finished iteration of a stored campaign reopened at its polishing phase or its report, so today's loop decides
the polish (or the report and its diagnosis) again and runs only the batteries that decision adds (the service
stopped while this runs).

Why: a tier B campaign is hours of DEM, and a change to the polishing rule changes nothing before the polish:
the design, the surfaces, the optimum and its confirmation batteries are what today's code would make again.
Rerunning them costs an hour for nothing; reopening keeps them, drops what came after the polish (the iteration's
report, its diagnosis batteries, any later iteration, the campaign's end) and lets the service's runner carry on
from the polish. That the kept batteries are today's loop's own is checked afterwards, not assumed:
``bench/diagnosis_dem.py`` replays the whole campaign through the notebook loop (``calibration.replay``), and a
battery today's code would not have run appears there as a difference. Session 37 used it on tier B's
hertz_strong (docs/diagnosis.md).

At the polish (``--phase polish``) only an iteration whose polish was skipped or took no step yet can be reopened: a polished one's
optimum moved, and its confirmation batteries were no longer its final ones. ``--keep-jacobian`` keeps such a polish's
first round (the Jacobian's points and the anchors, measured on the batteries) and drops only the rounds after it: the
state goes back to that round finished, so today's rule decides the steps from the same batteries (session 38: the
anchors' own steps, tried without rerunning hertz_strong's 48 batteries of round 0). At the report (``--phase report``) the
polish is kept and the diagnosis batteries are dropped with the report: a change to how the diagnosis decides
(``calibration.replicates``) is tried on the iteration's own optimum, its diagnosis batteries run again.

    python3 bench/reopen.py --data-dir /work/tierb/s37/hs2 --campaign 1 --iteration 2
    python3 bench/reopen.py --data-dir /work/tierb/s38/hs --campaign 1 --iteration 2 --keep-jacobian
    python3 bench/reopen.py --data-dir /work/tierb/s37/weak --campaign 1 --iteration 1 --phase report
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from sqlalchemy import create_engine, text

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from calibration.awaiting import ROUND  # noqa: E402  (a polish run's std_order: round x ROUND + index + 1)

AFTER = {"polish": ("polish", "report", "diagnosis", "diagnosed", "done"), "report": ("diagnosis", "diagnosed", "done")}


def _json(value):
    return json.loads(value) if isinstance(value, (str, bytes)) else value


def _rewound(polish: dict) -> dict:
    """A polish state that took no step, back to its first round (the Jacobian's) queued: its start point, its
    anchors as planned. ``calibration.polish.advance`` recomputes the Jacobian's target rows and the anchors' chi2
    from that round's batteries, so nothing the later rounds decided is kept."""
    if polish.get("steps") or polish.get("jacobian") != "batteries" or polish.get("stage") not in ("step", "done"):
        raise SystemExit("--keep-jacobian: only a polish whose Jacobian round was measured on the batteries and "
                         "that took no step can go back to that round")
    state = {k: v for k, v in polish.items() if k not in ("direction", "shrink", "trials")}
    state.update(stage="jacobian", round=0, batteries=0, steps=0)
    if state.get("anchors"):
        state["anchors"] = [{"held": a["held"], "parameters": a["parameters"]} for a in state["anchors"]]
    return state


def reopen(url: str, campaign_id: int, number: int, phase: str = "polish", keep_jacobian: bool = False) -> dict:
    """Reopen iteration ``number`` of campaign ``campaign_id`` at ``phase`` ("polish" or "report"); what was
    dropped. ``keep_jacobian`` (at the polish): keep the polish's first round and its state at that round."""
    engine = create_engine(url)
    with engine.begin() as db:
        campaign = db.execute(text("select status from campaigns where id = :c"), {"c": campaign_id}).first()
        if campaign is None:
            raise SystemExit(f"no campaign {campaign_id} in {url}")
        it = db.execute(text("select id, phase, optimum from campaign_iterations where campaign_id = :c and number = :n"),
                        {"c": campaign_id, "n": number}).first()
        if it is None:
            raise SystemExit(f"campaign {campaign_id} has no iteration {number}")
        if it[1] not in AFTER[phase]:
            raise SystemExit(f"iteration {number} is at its {it[1]} phase: nothing to reopen before the {phase}")
        optimum = dict(_json(it[2]) or {})
        polish = (optimum.pop("polish", None) or {}) if phase == "polish" else (optimum.get("polish") or {})
        if phase == "polish" and (polish.get("steps") or "surrogate_parameters" in optimum) and not keep_jacobian:
            raise SystemExit(f"iteration {number} was polished (its optimum moved off the surfaces'): only a skipped "
                             "polish can be reopened")
        if keep_jacobian:
            if phase != "polish":
                raise SystemExit("--keep-jacobian reopens at the polish")
            # no step was taken, so the polished optimum is the surfaces' own
            optimum["parameters"] = optimum.pop("surrogate_parameters", optimum.get("parameters"))
            optimum["polish"] = _rewound(polish)
        dropped_kinds = ("polish", "diagnosis") if phase == "polish" else ("diagnosis",)
        later = [row[0] for row in db.execute(text(
            "select id from campaign_iterations where campaign_id = :c and number > :n"), {"c": campaign_id, "n": number})]
        dropped = [row[0] for row in db.execute(text(
            "select id from campaign_runs where iteration_id in (select id from campaign_iterations where "
            "campaign_id = :c and number > :n)"), {"c": campaign_id, "n": number})]
        dropped += [row[0] for kind in dropped_kinds for row in db.execute(text(
            "select id from campaign_runs where iteration_id = :i and kind = :k and std_order >= :o"),
            {"i": it[0], "k": kind, "o": ROUND if keep_jacobian and kind == "polish" else 0})]
        for run_id in dropped:
            # a run's job is queued under "campaign:C:run:R" (service.campaigns.runner), and SQLite gives a new run
            # the highest id again: the dropped run's job keeps its results under a key no new run can ask for
            key = f"campaign:{campaign_id}:run:{run_id}"
            earlier = db.execute(text("select count(*) from jobs where idempotency_key like :k"),
                                 {"k": f"{key}:reopened%"}).scalar()
            db.execute(text("update jobs set idempotency_key = :new where idempotency_key = :k"),
                       {"new": f"{key}:reopened{earlier + 1}", "k": key})
            # and one not finished (queued, or running when the service was stopped) is not run for nothing
            db.execute(text("update jobs set status = 'cancelled', finished_at = CURRENT_TIMESTAMP, error = :e "
                            "where idempotency_key = :new and status in ('queued', 'running')"),
                       {"new": f"{key}:reopened{earlier + 1}", "e": "its campaign run was dropped by bench/reopen.py"})
            db.execute(text("delete from campaign_runs where id = :r"), {"r": run_id})
        for iteration_id in later:
            db.execute(text("delete from campaign_iterations where id = :i"), {"i": iteration_id})
        db.execute(text("update campaign_iterations set phase = :p, optimum = :o, report = null, "
                        "finished_at = null where id = :i"), {"p": phase, "o": json.dumps(optimum), "i": it[0]})
        db.execute(text("update campaigns set status = 'running', current_iteration = :n, error = null, "
                        "finished_at = null where id = :c"), {"n": number, "c": campaign_id})
    return {"campaign": campaign_id, "iteration": number, "phase": phase, "was": it[1], "campaign_was": campaign[0],
            "later_iterations_dropped": len(later), "runs_dropped": len(dropped), "polish_was": polish}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    where = ap.add_mutually_exclusive_group(required=True)
    where.add_argument("--data-dir", help="a service's data folder (its demcal.db); the service must be stopped")
    where.add_argument("--url", help="a database URL")
    ap.add_argument("--campaign", type=int, required=True)
    ap.add_argument("--iteration", type=int, required=True)
    ap.add_argument("--phase", choices=sorted(AFTER), default="polish", help="where the iteration starts again")
    ap.add_argument("--keep-jacobian", action="store_true",
                    help="at the polish: keep its first round (the Jacobian's batteries and the anchors) when it took "
                         "no step, and decide the steps again from them")
    args = ap.parse_args()
    url = args.url or f"sqlite:///{Path(args.data_dir) / 'demcal.db'}"
    print(json.dumps(reopen(url, args.campaign, args.iteration, args.phase, args.keep_jacobian), indent=1))


if __name__ == "__main__":
    sys.exit(main())
