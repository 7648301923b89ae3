"""An iteration's design through doe/, and its JSON view (natural and coded tables, aliases), which is
what an iteration stores and what rebuilds the design exactly (``Design.from_dict(view["doe"])``)."""
from __future__ import annotations

from typing import Any

from doe.designs import Design, augment_ccd, fractional_factorial, full_factorial
from doe.factors import DoeError

from calibration.errors import SettingsError
from calibration.settings import DesignIn, FactorIn


def build_design(factors: list[FactorIn], design: DesignIn, seed: int, field_prefix: str = "design.") -> Design:
    """doe/ design for the given factors; doe's complaints name the design setting they concern."""
    raw = [{"name": f.name, "low": f.low, "high": f.high, "unit": f.unit, "log": f.log} for f in factors]
    try:
        if design.type == "full":
            built = full_factorial(raw, center_runs=design.centre_runs, replicates=design.replicates,
                                   seed=seed, randomize=design.randomise)
        else:
            built = fractional_factorial(raw, design.generators, center_runs=design.centre_runs,
                                         replicates=design.replicates, seed=seed, randomize=design.randomise)
        if design.axial == "face":  # the factorial's centre runs serve the composite design too
            built = augment_ccd(built, "face", 0)
        return built
    except DoeError as exc:
        field = field_prefix + ("generators" if design.type == "fractional" else "type")
        raise SettingsError(str(exc), field) from exc


def design_view(design: Design) -> dict[str, Any]:
    """Design table in natural and coded units plus alias structure and resolution."""
    names = design.names
    rows = []
    for rec in design.records("std"):
        rows.append({
            "std_order": rec["std_order"], "run_order": rec["run_order"], "point_type": rec["point_type"],
            "replicate": rec["replicate"], "seed": rec["seed"],
            "natural": {f.name: rec[f.name] for f in design.factors},
            "coded": {f.name: rec[f"{f.letter}_coded"] for f in design.factors},
        })
    aliases = design.aliases.to_dict() if design.aliases else None
    return {
        "kind": design.kind,
        "factors": [f.to_dict() for f in design.factors],
        "generators": list(design.generators),
        "n_runs": design.n_runs,
        "resolution": aliases.get("resolution") if aliases else None,
        "resolution_label": aliases.get("resolution_label") if aliases else None,
        "aliases": aliases,
        "runs": rows,
        "factor_names": names,
        "notes": list(design.notes),
        "doe": design.to_dict(),
    }
