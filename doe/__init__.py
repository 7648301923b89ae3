"""Design of experiments and statistics for calibration; knows nothing of DEM.

Four calls carry a calibration campaign (all take and return JSON-friendly data):

    design = make_design(factors, center_runs=4, seed=1)          # or Design.from_dict(...)
    fits = fit_responses(design, results)                          # results aligned with design rows
    cal = calibrate(fits, targets, constraints=[...], priors=[...])
    check = confirm(fits, cal.parameters, observed)                # next design if it fails
"""
from .aliases import AliasStructure, alias_structure
from .confirm import ConfirmationResult, confirm, narrowed_factorial
from .constraints import LinearConstraint, NonlinearConstraint, Prior, Target, parse_constraint
from .designs import (Design, augment_ccd, foldover, fractional_factorial, full_factorial, make_design,
                      rotatable_alpha)
from .driver import AnalyticEvaluator, Evaluator, run_design
from .effects import EffectsResult, compute_effects, lenth
from .factors import DoeError, Factor, parse_factor
from .fit import AnovaRow, ResponseFit, fit_response, fit_responses
from .optimise import CalibrationResult, calibrate

__all__ = [
    "AliasStructure", "alias_structure", "ConfirmationResult", "confirm", "narrowed_factorial",
    "LinearConstraint", "NonlinearConstraint", "Prior", "Target", "parse_constraint", "Design",
    "augment_ccd", "foldover", "fractional_factorial", "full_factorial", "make_design", "rotatable_alpha",
    "AnalyticEvaluator", "Evaluator", "run_design", "EffectsResult", "compute_effects", "lenth",
    "DoeError", "Factor", "parse_factor", "AnovaRow", "ResponseFit", "fit_response", "fit_responses",
    "CalibrationResult", "calibrate",
]
