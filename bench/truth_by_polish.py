"""The truth judged by the polish's own objective at the polish's own seeds: was there a better point to find?

Why: tier B's "RMS within 1.1 x the truth's" reads the targets alone at fresh seeds, while the polish minimises the
targets' misfit and the measured priors' (a pycnometer, tilt tests) at the seeds it ran. Where the truth scores no
better than the chosen point on that objective, no choosing rule could have preferred it: what is left is the
measurements' own draw and the priors', not the polish. The scenario's truth (its measuring world's job, keyed by
seed, so the truth floor's batteries are shared) runs at the kept iteration's polish seeds and is judged as every
point the polish measured there (``calibration.polish._residuals``: the targets and the priors), beside them.

    python3 bench/truth_by_polish.py --data-dir DIR --rows rows.json --scenario hertz_strong

``--rows`` is the file ``diagnosis_dem.py --json`` wrote for the campaign in DIR (its campaign, kept iteration and
options); the truth's batteries are queued on a local service over DIR's database (8 on hertz_strong).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import diagnosis_dem as dd  # noqa: E402
import reanalyse as ra  # noqa: E402

from calibration import analysis, polish  # noqa: E402
from calibration import parameters as factor_paths  # noqa: E402


def _targets_chi2(res) -> float:
    return float(res.r_targets @ res.r_targets)


def _line(label: str, natural: dict, res) -> str:
    values = " ".join(f"{name.split('.')[-1]} {value:.4g}" for name, value in natural.items())
    return (f"{label:8s} chi2 {res.chi2():7.2f} (targets {_targets_chi2(res):6.2f}, priors "
            f"{float(res.prior_r @ res.prior_r):6.2f})  {values}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data-dir", required=True, help="the service's data folder the campaign ran in (its demcal.db)")
    ap.add_argument("--rows", required=True, help="diagnosis_dem.py's --json file for that folder")
    ap.add_argument("--scenario", required=True, choices=sorted(dd.SCENARIOS))
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    if not Path(args.rows).is_file() or not (Path(args.data_dir) / "demcal.db").is_file():
        raise SystemExit(f"no {args.rows}, or no demcal.db in {args.data_dir}")
    rows = {o["scenario"]: o for o in json.loads(Path(args.rows).read_text())}
    if args.scenario not in rows:
        raise SystemExit(f"{args.rows} has no row for {args.scenario}")
    row, sc = rows[args.scenario], dd.SCENARIOS[args.scenario]
    cid, number = row["campaign_id"], row.get("after_iteration") or 1
    url = f"sqlite:///{Path(args.data_dir).resolve() / 'demcal.db'}"
    settings, design_dict, design_runs, targets, optimum, _ = ra.load(url, cid, number)
    state = (optimum or {}).get("polish")
    if not state or "skipped" in state or "seeds" not in state:
        raise SystemExit(f"campaign {cid}'s iteration {number} did not polish")
    seeds = polish.seeds_of(state)
    options = {**dd.OPTIONS,
               "cct_window_stresses_pa": row.get("cct_window_stresses_pa") or dd.OPTIONS["cct_window_stresses_pa"]}
    svc = dd.Service(None, args.workers, args.data_dir)
    try:
        ids = dd.truth_jobs(svc, sc, seeds, row.get("evaluator") or "dem", options, row.get("form") == "reduced")
        truth_runs = [dd.responses_of(r) for r in dd._wait_jobs(svc, ids, 5.0)]
    finally:
        svc.close()
    design, models = analysis.fit(design_dict["doe"], design_runs, targets)
    modelled = [m for m in models if m.fit is not None]
    truth = {name: float(factor_paths.read(sc.parameters(), name)) for name in state["free"]}
    res_truth = polish._residuals(settings, design, modelled, truth, [list(r.values()) for r in truth_runs], seeds)
    print(f"{args.scenario}, campaign {cid} iteration {number}: the polish's objective at its {len(seeds)} seeds")
    print(_line("truth", truth, res_truth))
    chosen = None
    it = ra.stored_iteration(url, cid, number)
    for k, (natural, group) in enumerate(polish.measured_points(state, it.runs)):
        records = [list((g.responses or {}).values()) for g in group]
        res = polish._residuals(settings, design, modelled, natural, records, seeds)
        is_chosen = all(abs(natural[n] - state["theta"][n]) <= 1e-9 * max(1.0, abs(state["theta"][n]))
                        for n in state["free"])
        chosen = res.chi2() if is_chosen else chosen
        print(_line("chosen" if is_chosen else ("optimum" if k == 0 else f"point {k}"), natural, res))
    print(f"truth_chi2={res_truth.chi2():.2f} chosen_chi2={chosen if chosen is None else round(chosen, 2)} "
          f"truth_targets_chi2={_targets_chi2(res_truth):.2f} seeds={len(seeds)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
