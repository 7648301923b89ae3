"""Batteries an earlier iteration ran, reused by a later one: the loop's store of runs, read by the design.

Why: a loop that adds an effect as a fifth factor used to start its design from nothing, although the
iteration it builds on had already run the model at every one of the new design's points with the
effect off (its design runs), near the optimum (confirmation, polishing) and with the effect switched on
a little (the diagnosis). Nineteen batteries became nineteen more. Here every evaluated battery of the
loop is a point of the model it ran, (complete micro parameters, seed) -> responses; an iteration reuses
those its own model can express:

* **The same model point.** A battery counts for an iteration when its complete parameters are those of
  the iteration's model at some factor values inside the iteration's box: the fixed parameters must agree
  and every factor's value is read from the battery (an effect absent from it is at its ``off_value``,
  where the candidate registry says it vanishes: rolling friction 0, aspect ratio 1). A battery of a model
  with another effect switched on, or other fixed parameters, never counts.
* **Design points first.** A design row whose coded point such a battery sits on is not run again: the
  battery, with its seed and responses, becomes that row (an added effect's "off" face is the previous
  design: ``calibration.adding`` keeps the previous generators so the faces coincide, as a foldover builds
  on a fraction).
* **The same set-up.** A battery counts only where it ran what the iteration runs: the same test, preset or
  resolution with its rig and particles, battery options and evaluator (``setup_key``). An iteration that
  changes the options (other loads) or the resolution starts from its own batteries.
* **Every other battery informs the fit.** The rest (centre runs of the face, confirmation, polishing and
  diagnosis batteries) are appended as rows of type "other": the response surfaces are fitted on them too.
* **Pure error from true replicates only.** Replicates are batteries at one point with different seeds,
  whichever phase ran them; reused ones count towards the centre replicates' pure error, so the new
  design runs only as many centre runs as the configured pure-error degrees of freedom still need (and
  at least one, for the centre of the new box). A reused battery keeps its seed, new ones never share it.

The statistics downstream do not change: the lack of fit and the diagnosis judge the new iteration's own
confirmation batteries (seeds never used before), so a reused battery never meets itself in a residual.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, replace
from typing import Any, Iterable, Sequence

import numpy as np

from doe.designs import Design, draw_seeds, replicate_index

from . import parameters as factor_paths

TOLERANCE = 1e-9


def _vanished(parameters: dict[str, Any]) -> dict[str, Any]:
    """``parameters`` with every candidate effect at its vanishing strength removed (an effect at
    ``off_value`` is the model without it), so two spellings of one model compare equal."""
    from engine.candidates import candidates

    out = dict(parameters)
    effects = dict(out.get("effects") or {})
    for c in candidates().values():
        if c.off_value is None:
            continue
        value = factor_paths.read(out, c.factor)
        if value is None or abs(value - c.off_value) > TOLERANCE * max(1.0, abs(c.off_value)):
            continue
        if c.effect_name is not None:
            effects.pop(c.effect_name, None)
        else:
            out.pop(c.factor, None)
    out["effects"] = effects
    return out


def canonical(parameters: dict[str, Any]) -> str:
    """One text per model point: the complete micro parameters (defaults filled in) with vanished
    effects dropped."""
    from engine.lab.spec import MicroParameters

    full = MicroParameters.model_validate(_vanished(parameters)).model_dump(mode="json")
    return json.dumps(_vanished(full), sort_keys=True)


def _off(factor: str) -> float | None:
    """The value a factor has in a model that does not mention it: a candidate's vanishing strength, or
    the micro parameter's default."""
    from engine.candidates import candidates
    from engine.lab.spec import MicroParameters

    for c in candidates().values():
        if c.factor == factor and c.off_value is not None:
            return float(c.off_value)
    if "." not in factor:
        default = MicroParameters.model_fields[factor].default
        return float(default) if isinstance(default, (int, float)) else None
    return None


def coordinates(parameters: dict[str, Any], fixed: dict[str, Any], factors: Sequence) -> dict[str, float] | None:
    """The factor values at which the model (``fixed`` plus ``factors``) is the point ``parameters``,
    or None when no factor values make it so (another effect on, other fixed parameters)."""
    values: dict[str, float] = {}
    for f in factors:
        value = factor_paths.read(parameters, f.name)
        value = _off(f.name) if value is None else value
        if value is None:
            return None
        values[f.name] = value
    try:
        same = canonical(factor_paths.apply(fixed, values)) == canonical(parameters)
    except ValueError:  # the values make no valid micro parameter set
        return None
    return values if same else None


@dataclass(frozen=True)
class Earlier:
    """An evaluated battery of an earlier iteration as a point of the current model."""

    iteration: int
    kind: str
    std_order: int
    seed: int
    natural: dict[str, float]          # in the current iteration's factors
    coded: tuple[float, ...]           # the same, coded in the current box
    responses: dict[str, Any]
    job_id: int | None

    @property
    def source(self) -> str:
        return f"iteration {self.iteration} {self.kind} run {self.std_order}"

    def provenance(self) -> dict[str, Any]:
        return {"iteration": self.iteration, "kind": self.kind, "std_order": self.std_order, "seed": self.seed,
                "job_id": self.job_id}


def _fixed_of(parameters: dict[str, Any]) -> dict[str, Any]:
    """An iteration's fixed parameters with its fixed effects (``machine.iteration_parameters``' split undone)."""
    fixed = dict(parameters.get("fixed") or {})
    if parameters.get("effects"):
        fixed["effects"] = parameters["effects"]
    return fixed


def lab_json(settings) -> dict[str, Any]:
    """Where the settings' batteries run (``LoopSettings.lab``: the preset, or the resolution with its rig and
    particles) as JSON, as an iteration records it (the material card of that iteration reads it back)."""
    return {k: (v.model_dump(mode="json") if hasattr(v, "model_dump") else v) for k, v in settings.lab().items()}


def setup_key(settings, evaluator: str | None) -> str:
    """What a battery ran besides its micro parameters, as one digest: the test, the preset or the resolution
    with its rig and particles, the battery options and the evaluator (``machine.iteration_parameters`` keeps
    it per iteration)."""
    import hashlib

    what = {"test": settings.test, "lab": lab_json(settings), "options": settings.options, "evaluator": evaluator}
    return hashlib.sha256(json.dumps(what, sort_keys=True, default=str).encode()).hexdigest()


def same_setup(earlier: dict[str, Any], current: dict[str, Any] | None) -> bool:
    """Did an earlier iteration (its stored parameters) run in the current one's set-up? Compared on the
    ``setup_key`` both carry; an iteration stored before the key existed could not change its rig or resolution,
    so there its options, preset and evaluator are compared."""
    if current is None:
        return True
    if earlier.get("setup_key") and current.get("setup_key"):
        return earlier["setup_key"] == current["setup_key"]
    return all(earlier.get(k) == current.get(k) for k in ("options", "fidelity", "evaluator"))


def earlier_runs(iterations: Iterable, number: int, fixed: dict[str, Any], factors: Sequence,
                 current: dict[str, Any] | None = None) -> list[Earlier]:
    """Every evaluated battery of iterations before ``number`` that is a point of the model (``fixed``,
    ``factors``) inside its box and ran in the set-up of ``current`` (the iteration's stored parameters,
    ``same_setup``), each battery once (a battery reused by iteration 2 is iteration 1's)."""
    from doe.factors import as_factors

    box = as_factors([{"name": f.name, "low": f.low, "high": f.high, "unit": f.unit, "log": f.log} for f in factors])
    out: list[Earlier] = []
    seen: set[tuple[int, str]] = set()
    for it in sorted((i for i in iterations if i.number < number), key=lambda i: i.number):
        if not same_setup(it.parameters or {}, current):
            continue
        its_fixed = _fixed_of(it.parameters or {})
        for run in sorted(it.runs, key=lambda r: (str(r.kind), r.std_order)):
            if run.responses is None or getattr(run, "reused_from", None):
                continue
            point = factor_paths.apply(its_fixed, run.natural)
            key = (int(run.seed), canonical(point))
            if key in seen:
                continue
            seen.add(key)
            natural = coordinates(point, fixed, factors)
            if natural is None:
                continue
            coded = tuple(float(f.to_coded(natural[f.name])) for f in box)
            if any(abs(u) > 1 + 1e-9 for u in coded):
                continue
            out.append(Earlier(it.number, str(getattr(run.kind, "value", run.kind)), int(run.std_order), int(run.seed),
                               natural, tuple(0.0 if abs(u) < TOLERANCE else u for u in coded), dict(run.responses),
                               run.job_id))
    return out


def _replicate_df(points: Iterable[tuple[float, ...]]) -> int:
    """Pure-error degrees of freedom of runs at these points: runs minus distinct points."""
    points = [tuple(round(u, 9) for u in p) for p in points]
    return len(points) - len(set(points))


@dataclass
class Reused:
    """The design with earlier batteries in it: ``sources[i]`` is None for a row to run, else the battery
    that is that row (std order i + 1)."""

    design: Design
    sources: list[Earlier | None]

    @property
    def new_runs(self) -> int:
        return sum(s is None for s in self.sources)


def with_earlier(design: Design, earlier: Sequence[Earlier]) -> Reused:
    """``design`` with earlier batteries on its points and after its rows (module docstring)."""
    if not earlier:
        return Reused(design, [None] * design.n_runs)
    free = list(earlier)
    sources: list[Earlier | None] = []
    keep: list[int] = []
    coded = design.coded
    centre_rows = [i for i, t in enumerate(design.point_type) if t == "center"]
    for i in range(design.n_runs):
        match = next((e for e in free if np.allclose(e.coded, coded[i], atol=1e-9)), None)
        if match is not None:
            free.remove(match)
        sources.append(match)
        keep.append(i)
    # centre runs still to run: the configured pure-error degrees of freedom, less those the reused
    # batteries already bring, but one at least (the new box's centre, for the curvature)
    brought = _replicate_df([e.coded for e in earlier])
    to_run = [i for i in centre_rows if sources[i] is None]
    drop = set(to_run[max(1, len(to_run) - brought):])
    keep = [i for i in keep if i not in drop]
    rows = [coded[i] for i in keep] + [np.array(e.coded) for e in free]
    types = [design.point_type[i] for i in keep] + ["other"] * len(free)
    sources = [sources[i] for i in keep] + list(free)
    taken = {e.seed for e in earlier}
    seeds = [int(design.seed[i]) for i in keep] + [e.seed for e in free]
    rng = np.random.default_rng([design.base_seed, 34, len(earlier)])
    for j, src in enumerate(sources):
        if src is not None:
            seeds[j] = src.seed
        elif seeds[j] in taken:
            seeds[j] = int(draw_seeds(rng, 1, taken | set(seeds))[0])
        taken.add(seeds[j])
    # the rows to run keep the design's randomised order among themselves; reused rows come after
    order = [int(design.run_order[i]) for i in keep] + [0] * len(free)
    to_do = sorted((o, j) for j, o in enumerate(order) if sources[j] is None)
    done = [j for j in range(len(sources)) if sources[j] is not None]
    run_order = np.zeros(len(sources), dtype=np.int64)
    for position, (_, j) in enumerate(to_do, start=1):
        run_order[j] = position
    for position, j in enumerate(done, start=len(to_do) + 1):
        run_order[j] = position
    rows_arr = np.vstack(rows)
    on_points = sum(s is not None for s in sources) - len(free)
    notes = list(design.notes) + [
        f"{on_points + len(free)} batteries of earlier iterations reused ({on_points} on design points, "
        f"{len(free)} as further points of the fit); {len(drop)} centre run(s) not run again: reused "
        f"replicates bring {brought} pure-error degrees of freedom"]
    merged = replace(design, coded=rows_arr, point_type=types, run_order=run_order,
                     replicate=replicate_index(rows_arr), seed=np.array(seeds, dtype=np.int64),
                     block=np.array([1 if s is None else 0 for s in sources], dtype=np.int64) + 1,
                     notes=notes, aliases=None)
    return Reused(merged, sources)
