"""Confirmation of a calibrated optimum, and what to run next if it fails.

A confirmation run at the optimum must land inside each model's prediction
interval. If it does not, iterating the optimiser on the same models is blind:
either the model form is wrong (curvature or lack of fit -> augment to a central
composite design and fit squares) or the box is too wide for a low-order model
to be accurate near the optimum (-> a smaller factorial centred on the optimum).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .designs import Design, augment_ccd, fractional_factorial
from .factors import DoeError
from .fit import ResponseFit


@dataclass
class ConfirmationResult:
    parameters: dict[str, float]
    responses: list[dict]
    confirmed: bool
    verdict: str
    reason: str
    next_design_kind: str | None
    next_design: Design | None

    def to_dict(self) -> dict:
        return {"parameters": dict(self.parameters), "responses": list(self.responses),
                "confirmed": self.confirmed, "verdict": self.verdict, "reason": self.reason,
                "next_design_kind": self.next_design_kind,
                "next_design": self.next_design.to_dict() if self.next_design is not None else None}

    def summary(self) -> str:
        from .report import table
        t = table(["Response", "Observed", "Predicted", "PI low", "PI high", "Inside"],
                  [[r["response"], r["observed"], r["predicted"], r["pi_low"], r["pi_high"],
                    "-" if r["inside"] is None else r["inside"]] for r in self.responses])
        out = [f"{self.verdict}: {self.reason}", t]
        if self.next_design is not None:
            out.append("Proposed next design\n" + self.next_design.summary())
        return "\n\n".join(out)


def _model_form_inadequate(fit: ResponseFit, alpha: float) -> bool:
    for row in (fit.curvature_row, fit.lack_of_fit_row):
        if row is not None and row.p_value is not None and row.p_value < alpha:
            return True
    return False


def narrowed_factorial(design: Design, centre: dict[str, float], shrink: float = 0.5,
                       center_runs: int = 3, seed: int = 0) -> Design:
    """Same fraction, each factor's range scaled by `shrink` around `centre`, kept inside the old box."""
    if not 0 < shrink < 1:
        raise DoeError("shrink must lie between 0 and 1")
    factors = []
    for f in design.factors:
        half = shrink
        c = float(np.clip(f.to_coded(centre[f.name]), -1 + half, 1 - half))
        factors.append(f.with_levels(float(f.to_natural(c - half)), float(f.to_natural(c + half))))
    gens = design.generators if design.generators else []
    return fractional_factorial(factors, gens, center_runs=center_runs, seed=seed)


def confirm(models, parameters: dict[str, float], observed: dict[str, float], *, alpha: float = 0.05,
            shrink: float = 0.5, center_runs: int = 3, seed: int = 0, n_observations: int = 1) -> ConfirmationResult:
    """Compare confirmation-run responses (each the mean of ``n_observations`` runs at `parameters`)
    with the models' prediction intervals for such a mean."""
    if isinstance(models, (list, tuple)):
        models = {m.response: m for m in models}
    if not observed:
        raise DoeError("no observed responses to confirm")
    rows, misses, no_pi = [], [], []
    for name, value in observed.items():
        if name not in models:
            raise DoeError(f"observed response {name!r} has no fitted model")
        pred = models[name].predict([parameters], alpha, n_future=n_observations)[0]
        inside = None
        if pred["pi_low"] is not None:
            inside = bool(pred["pi_low"] <= float(value) <= pred["pi_high"])
            if not inside:
                misses.append(name)
        else:
            no_pi.append(name)
        rows.append({"response": name, "observed": float(value), "predicted": pred["mean"],
                     "pi_low": pred["pi_low"], "pi_high": pred["pi_high"], "inside": inside})
    if not misses and not no_pi:
        return ConfirmationResult(dict(parameters), rows, True, "confirmed",
                                  f"every response lies inside its {100 * (1 - alpha):.0f}% prediction interval",
                                  None, None)
    fits = [models[n] for n in misses + no_pi]
    design = fits[0].design
    has_axial = any(t == "axial" for t in design.point_type)
    inadequate = [f.response for f in fits if _model_form_inadequate(f, alpha)]
    if no_pi and not misses:
        verdict = "not testable"
        reason = (f"no prediction interval for {', '.join(no_pi)} (no error estimate); "
                  "replicated centre runs are needed")
    else:
        verdict = "not confirmed"
        reason = f"{', '.join(misses)} outside the prediction interval"
    if (inadequate or no_pi) and not has_axial:
        kind = "augment_ccd"
        nxt = augment_ccd(design, "face", center_runs)
        if inadequate:
            reason += (f"; curvature or lack of fit in {', '.join(inadequate)}: augment to a face-centred CCD "
                       "to fit squared terms")
        else:
            reason += "; augment to a face-centred CCD, whose replicated centre runs give an error estimate"
    else:
        kind = "narrowed_factorial"
        nxt = narrowed_factorial(design, parameters, shrink, center_runs, seed)
        reason += f"; refit over a factorial {shrink:g}x the range centred on the optimum"
    return ConfirmationResult(dict(parameters), rows, False, verdict, reason, kind, nxt)
