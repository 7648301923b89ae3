"""Replaying stored batteries: a batch evaluator that answers from runs made earlier.

Why: a campaign's batteries are the expensive part (minutes each on the DEM engine); its verdicts are
cheap functions of them. Replaying a campaign's stored runs through ``calibration.loop`` reproduces
its report, diagnosis and automatic decisions in a notebook, without the service or the engine, and
checks that the service and the notebook loop are one loop. A battery the stored campaign never ran
is an error naming it, never a guess.
"""
from __future__ import annotations

import json
from typing import Any, Iterable, Mapping, Sequence

from . import parameters as factor_paths
from .evaluators import RunRequest


def _key(parameters: Mapping[str, Any], seed: int) -> str:
    return json.dumps([dict(parameters), int(seed)], sort_keys=True, default=float)


def iteration_fixed(iteration_parameters: Mapping[str, Any]) -> dict[str, Any]:
    """The fixed micro parameters an iteration ran with (its active effects included)."""
    fixed = dict(iteration_parameters.get("fixed") or {})
    if iteration_parameters.get("effects"):
        fixed["effects"] = iteration_parameters["effects"]
    return fixed


class ReplayEvaluator:
    """Answers (parameters, seed) with the stored responses of the run made there.

    ``iterations``: objects or dicts with ``parameters`` (what the iteration ran with) and ``runs``
    (each with ``natural``, ``seed`` and ``responses``), as the service's iteration view has them.
    """

    def __init__(self, iterations: Iterable[Any]):
        self.stored: dict[str, list[dict]] = {}
        self.runs = 0
        for it in iterations:
            get = it.get if isinstance(it, Mapping) else lambda k, it=it: getattr(it, k)
            fixed = iteration_fixed(get("parameters") or {})
            for run in get("runs"):
                rget = run.get if isinstance(run, Mapping) else lambda k, run=run: getattr(run, k)
                if rget("responses") is None:
                    continue
                key = _key(factor_paths.apply(fixed, rget("natural")), rget("seed"))
                self.stored[key] = list(rget("responses").values())

    def __call__(self, requests: Sequence[RunRequest]) -> list[list[dict]]:
        out = []
        for parameters, seed in requests:
            found = self.stored.get(_key(parameters, seed))
            if found is None:
                raise KeyError(f"no stored battery at seed {seed} with parameters {dict(parameters)}")
            out.append(found)
            self.runs += 1
        return out


def differences(stored: Sequence[Mapping[str, Any]], replayed: Sequence[Any], rel: float = 1e-9) -> list[str]:
    """Where a replay disagrees with the stored iterations (``[]``: the same loop): per iteration the
    verdict, the optimum (relative ``rel``), the diagnosis's ranking, the automatic mode's added effect,
    decision and stop reason."""
    out = []
    if [s["number"] for s in stored] != [r.number for r in replayed]:
        return [f"iterations {[s['number'] for s in stored]} stored, {[r.number for r in replayed]} replayed"]
    for s, r in zip(stored, replayed):
        n, sr, rr = s["number"], s.get("report") or {}, r.report or {}
        if rr.get("verdict") != sr.get("verdict"):
            out.append(f"iteration {n}: verdict {rr.get('verdict')!r}, stored {sr.get('verdict')!r}")
        so, ro = sr.get("optimum") or {}, rr.get("optimum") or {}
        if so.keys() != ro.keys():
            out.append(f"iteration {n}: optimum of {sorted(ro)}, stored {sorted(so)}")
        for name in so.keys() & ro.keys():
            if abs(ro[name] - so[name]) > rel * abs(so[name]):
                out.append(f"iteration {n}: {name} = {ro[name]!r}, stored {so[name]!r}")
        ranking = lambda rep: [x["effect"] for x in (rep.get("diagnosis") or {}).get("ranking", [])]  # noqa: E731
        if ranking(rr) != ranking(sr):
            out.append(f"iteration {n}: ranking {ranking(rr)}, stored {ranking(sr)}")
        auto_s, auto_r = sr.get("automatic") or {}, rr.get("automatic") or {}
        for key in ("next_effect", "stop_reason"):
            if auto_r.get(key) != auto_s.get(key):
                out.append(f"iteration {n}: {key} {auto_r.get(key)!r}, stored {auto_s.get(key)!r}")
        accepted = lambda a: (a.get("decision") or {}).get("accepted")  # noqa: E731
        if accepted(auto_r) != accepted(auto_s):
            out.append(f"iteration {n}: decision accepted {accepted(auto_r)}, stored {accepted(auto_s)}")
    return out
