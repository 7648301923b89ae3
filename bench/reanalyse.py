"""An iteration of a stored campaign analysed again by today's code, from its stored batteries: no DEM run.

Why: a campaign's batteries are hours of DEM; its surfaces, optimum and predictions are cheap functions of them.
When the analysis changes (how surfaces are fitted, which runs they rest on), this shows what the change does to a
real campaign before any battery is run again: each target's surface (the runs it rests on, its scale, the terms
kept), the surfaces' optimum, and the surfaces against the iteration's own confirmation batteries at the optimum
it stored (mean over the seeds, and whether it lies inside the surface's 95 % prediction interval for that mean).
Session 34 used it on hertz_strong's stopped second iteration (docs/diagnosis.md).

With --diagnosis it also diagnoses the iteration again from its stored diagnosis batteries (its stored plan, the
batteries at its final optimum): the verdict, ranking, and the candidates unseen or undetermined, as today's
code words them. The settings are the campaign's configuration, which is its last iteration's: the diagnosis of
an earlier iteration is computed with the last one's settings (its priors, options).

    python3 bench/reanalyse.py --data-dir /work/tierb/s33/hs --campaign 1 --iteration 2
    python3 bench/reanalyse.py --data-dir /work/tierb/s35/weak --campaign 1 --iteration 2 --diagnosis
    python3 bench/reanalyse.py --url postgresql+psycopg://... --campaign 7 --iteration 1
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import types
from pathlib import Path

import numpy as np
from sqlalchemy import create_engine, text

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from calibration import analysis, fits  # noqa: E402
from calibration.settings import LoopSettings  # noqa: E402
from doe.designs import Design  # noqa: E402


def _json(value):
    return json.loads(value) if isinstance(value, (str, bytes)) else value


def load(url: str, campaign_id: int, number: int):
    """(settings, the iteration's design dict, its design runs, the material's targets, stored optimum, confirmations)."""
    with create_engine(url).connect() as db:
        row = db.execute(text("select config, material_id from campaigns where id = :c"), {"c": campaign_id}).first()
        if row is None:
            raise SystemExit(f"no campaign {campaign_id} in {url}")
        config, material_id = _json(row[0]), row[1]
        it = db.execute(text("select id, design, optimum from campaign_iterations where campaign_id = :c and "
                             "number = :n"), {"c": campaign_id, "n": number}).first()
        if it is None or it[1] is None:
            raise SystemExit(f"campaign {campaign_id} has no designed iteration {number}")
        runs = {kind: [types.SimpleNamespace(std_order=r[0], seed=r[1], responses=_json(r[2]))
                       for r in db.execute(text("select std_order, seed, responses from campaign_runs where "
                                                "iteration_id = :i and kind = :k order by std_order"),
                                           {"i": it[0], "k": kind})]
                for kind in ("design", "confirmation")}
        targets = [dict(test=r[0], quantity=r[1], condition=_json(r[2]) or {}, unit=r[3], values=_json(r[4]),
                        stated_uncertainty=r[5], id=r[6])
                   for r in db.execute(text('select test, quantity, condition, unit, "values", stated_uncertainty, id '
                                            "from measurements where material_id = :m"), {"m": material_id})]
    settings = LoopSettings.model_validate({k: v for k, v in config.items() if k in LoopSettings.model_fields})
    if any(r.responses is None for r in runs["design"]):
        raise SystemExit(f"iteration {number}'s design batteries have not all run")
    return settings, _json(it[1]), runs["design"], targets, _json(it[2]), runs["confirmation"]


def stored_iteration(url: str, campaign_id: int, number: int):
    """The iteration as the loop's phases read it: its runs (every kind, with ids and parameters), optimum and
    report."""
    with create_engine(url).connect() as db:
        it = db.execute(text("select id, optimum, report from campaign_iterations where campaign_id = :c and "
                             "number = :n"), {"c": campaign_id, "n": number}).first()
        runs = [types.SimpleNamespace(id=r[0], kind=r[1], std_order=r[2], seed=r[3], responses=_json(r[4]),
                                      natural=_json(r[5]))
                for r in db.execute(text("select id, kind, std_order, seed, responses, natural from campaign_runs "
                                         "where iteration_id = :i order by id"), {"i": it[0]})]
    return types.SimpleNamespace(number=number, runs=runs, optimum=_json(it[1]), report=_json(it[2]) or {})


def diagnose_again(settings, design: dict, design_runs, targets, it) -> dict:
    """The iteration's diagnosis computed by today's code from its stored batteries (as calibration.machine's
    diagnosis phase computes it)."""
    from calibration import attribute, polish
    from calibration.vocabulary import RunKind

    plan = [(p["effect"], p["seed"], p.get("probe", attribute.STEP)) for p in it.report.get("diagnosis_plan") or []]
    runs = sorted((r for r in it.runs if r.kind == RunKind.DIAGNOSIS), key=lambda r: r.std_order)
    if not plan or len(runs) < len(plan) or any(r.responses is None for r in runs[:len(plan)]):
        raise SystemExit(f"iteration {it.number} has no complete stored diagnosis to compute again")
    final = polish.final_runs(it)
    return analysis.diagnose(settings, design["doe"], design_runs, targets, it.optimum,
                             [list((r.responses or {}).values()) for r in final], [r.seed for r in final],
                             [(name, seed, list((r.responses or {}).values()), probe)
                              for (name, seed, probe), r in zip(plan, runs)])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    where = ap.add_mutually_exclusive_group(required=True)
    where.add_argument("--data-dir", help="a service's data folder (its demcal.db)")
    where.add_argument("--url", help="a database URL")
    ap.add_argument("--campaign", type=int, required=True)
    ap.add_argument("--iteration", type=int, required=True)
    ap.add_argument("--diagnosis", action="store_true", help="also diagnose the iteration again from its stored "
                    "diagnosis batteries")
    args = ap.parse_args()
    url = args.url or f"sqlite:///{Path(args.data_dir) / 'demcal.db'}"
    settings, design, runs, targets, stored_optimum, confirmations = load(url, args.campaign, args.iteration)
    result = analysis.analyse(settings, design["doe"], runs, targets)
    _, models = fits.fitted(design["doe"], analysis._runs(Design.from_dict(design["doe"]), runs),
                            analysis._measured(targets))
    print("surfaces:")
    for m in models:
        if m.fit is None:
            print(f"  {m.target.key.name}: {m.status} ({m.error})")
            continue
        print(f"  {m.key.name}: {m.fit.n} of {len(m.values)} runs, scale {m.fit.transform}, terms "
              f"{' '.join(m.fit.term_labels)}")
    print("optimum of today's surfaces:")
    for name, value in result["optimum"]["parameters"].items():
        print(f"  {name} = {value:.6g}")
    if stored_optimum and confirmations:
        point = stored_optimum["parameters"]
        print(f"today's surfaces at the stored optimum against its {len(confirmations)} confirmation batteries:")
        for m in models:
            values = [r.responses[m.key.name]["value"] for r in confirmations
                      if m.fit is not None and m.key.name in (r.responses or {})]
            if not values:
                continue
            p = m.fit.predict([point], n_future=len(values))[0]
            mean = float(np.mean(values))
            inside = p["pi_low"] is not None and p["pi_low"] <= mean <= p["pi_high"]
            err = 100 * (p["mean"] - mean) / abs(mean) if mean else math.nan
            print(f"  {m.key.name:55s} batteries {mean:.4g}  surface {p['mean']:.4g} [{p['pi_low']:.4g}, "
                  f"{p['pi_high']:.4g}] ({err:+.0f} %){'' if inside else '  OUTSIDE'}")
    if args.diagnosis:
        it = stored_iteration(url, args.campaign, args.iteration)
        d = diagnose_again(settings, design, runs, targets, it)
        stored = (it.report.get("diagnosis") or {}).get("verdict")
        print(f"diagnosis by today's code: {d['verdict']} (stored: {stored})\n  {d['message']}")
        for row in d["ranking"]:
            print(f"  {row['effect']:20s} LM {row['lm']:.3g}  Holm p {row['p_holm']:.3g}  probe noise "
                  f"{row['signature_noise'] if row['signature_noise'] is None else round(row['signature_noise'], 3)}")
        print(f"  unseen: {[u['effect'] for u in d['unseen']]}  undetermined: "
              f"{[u['effect'] for u in d['undetermined']]}  measure next: {d['measure_next']}")


if __name__ == "__main__":
    main()
