"""Design of experiments and statistics for calibration; knows nothing of DEM.

Four calls carry a calibration campaign (all take and return JSON-friendly data):

    design = make_design(factors, center_runs=4, seed=1)          # or Design.from_dict(...)
    fits = fit_responses(design, results)                          # results aligned with design rows
    cal = calibrate(fits, targets, constraints=[...], priors=[...])
    check = confirm(fits, cal.parameters, observed)                # next design if it fails
"""
import importlib

# name -> submodule; resolved on first use (PEP 562) so that `import doe` (e.g. by the CLI) does not
# pay for pyDOE3 and statsmodels until a design or a fit is made
_WHERE = {
    "AliasStructure": "aliases", "alias_structure": "aliases",
    "ConfirmationResult": "confirm", "confirm": "confirm", "narrowed_factorial": "confirm",
    "LinearConstraint": "constraints", "NonlinearConstraint": "constraints", "Prior": "constraints",
    "Target": "constraints", "parse_constraint": "constraints",
    "Design": "designs", "augment_ccd": "designs", "foldover": "designs", "fractional_factorial": "designs",
    "full_factorial": "designs", "make_design": "designs", "rotatable_alpha": "designs",
    "AnalyticEvaluator": "driver", "Evaluator": "driver", "run_design": "driver",
    "EffectsResult": "effects", "compute_effects": "effects", "lenth": "effects",
    "DoeError": "factors", "Factor": "factors", "parse_factor": "factors",
    "AnovaRow": "fit", "ResponseFit": "fit", "fit_response": "fit", "fit_responses": "fit",
    "CalibrationResult": "optimise", "calibrate": "optimise",
}


def __getattr__(name: str):
    if name in _WHERE:
        value = getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'doe' has no attribute {name!r}")


__all__ = [
    "AliasStructure", "alias_structure", "ConfirmationResult", "confirm", "narrowed_factorial",
    "LinearConstraint", "NonlinearConstraint", "Prior", "Target", "parse_constraint", "Design",
    "augment_ccd", "foldover", "fractional_factorial", "full_factorial", "make_design", "rotatable_alpha",
    "AnalyticEvaluator", "Evaluator", "run_design", "EffectsResult", "compute_effects", "lenth",
    "DoeError", "Factor", "parse_factor", "AnovaRow", "ResponseFit", "fit_response", "fit_responses",
    "CalibrationResult", "calibrate",
]
