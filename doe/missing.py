"""A response some runs lack: the largest model the runs that hold a value can estimate.

Why: a simulated test can fail to give a value at some design points (a DEM hold that does not settle at
a stiff corner, a fill that never comes to rest) while the other runs give it. The design's full model
(main effects and every two-factor interaction of a resolution V fraction) then has more coefficients
than the remaining points can tell apart, and refusing to fit would leave that target out of the
calibration altogether, although the runs that hold it still say how the factors move it. A practitioner
faced with missing runs fits a smaller model: the main effects, which a fraction with a few corners lost
still estimates, and those interactions the remaining runs can separate and the data support. Here that
is forward selection under hierarchy: every estimable main effect, then, one at a time, the estimable
interaction that lowers the residual sum of squares most, while its partial F test has p <= ``alpha_in``
and the model keeps ``min_error_df`` residual degrees of freedom for its error estimate. The fit's
``reduction_log`` names the runs left out, the terms kept and the terms that could not be estimated, so a
report says the surface rests on fewer points than the design had.

A response every run holds is fitted with the full model exactly as ``fit_response`` would, on the scale
doe.transform chooses (a power law of a log-scaled factor is fitted to ln(y)).
"""
from __future__ import annotations

import numpy as np
from scipy import stats

from .designs import Design
from .factors import DoeError
from .fit import ResponseFit, default_terms, fit_response
from .lstsq import rank, residual_ss
from .terms import model_matrix, parents, sort_terms, term_label
from .transform import choose as choose_transform, forward

ALPHA_IN = 0.10
MIN_ERROR_DF = 2


def estimable_terms(design: Design, y, terms=None, alpha_in: float = ALPHA_IN,
                    min_error_df: int = MIN_ERROR_DF) -> tuple[list, list]:
    """(kept, not kept) terms of ``terms`` (default: the design's full model) for the runs where ``y`` is finite.

    Main effects enter in order while each adds a direction the runs can estimate; higher-order terms
    whose parents are in enter by forward selection (largest drop in the residual sum of squares first,
    partial F with p <= ``alpha_in``), as long as ``min_error_df`` residual degrees of freedom remain.
    """
    y = np.asarray(y, dtype=float).reshape(-1)
    ok = np.isfinite(y)
    coded, y = design.coded[ok], y[ok]
    n = y.size
    terms = sort_terms(default_terms(design) if terms is None else terms)
    kept = estimable_mains(coded, terms, min_error_df)
    rest = [t for t in terms if sum(t) > 1]
    while True:
        X = model_matrix(coded, kept)
        sse_now = residual_ss(X, y)
        best = None
        for t in rest:
            if t in kept or not set(parents(t)) <= set(kept):
                continue
            trial = model_matrix(coded, kept + [t])
            df_resid = n - trial.shape[1]
            if rank(trial) < trial.shape[1] or df_resid < min_error_df:
                continue
            sse = residual_ss(trial, y)
            if best is None or sse < best[1]:
                best = (t, sse, df_resid)
        if best is None:
            break
        t, sse, df_resid = best
        if sse <= 0.0:
            p = 0.0 if sse_now > 0 else 1.0
        else:
            p = float(stats.f.sf((sse_now - sse) / (sse / df_resid), 1, df_resid))
        if p > alpha_in:
            break
        kept.append(t)
    return sort_terms(kept), [t for t in terms if t not in kept]


def estimable_mains(coded: np.ndarray, terms, min_error_df: int = MIN_ERROR_DF) -> list:
    """The main effects of ``terms`` the runs ``coded`` can estimate, taken in order while each adds a direction
    and ``min_error_df`` residual degrees of freedom remain (it depends on the runs only, not on a response)."""
    kept: list = []
    for t in (t for t in sort_terms(terms) if sum(t) == 1):
        trial = model_matrix(coded, kept + [t])
        if rank(trial) == trial.shape[1] and coded.shape[0] - trial.shape[1] >= min_error_df:
            kept.append(t)
    return kept


def fit_available(design: Design, y, response: str = "y", alpha: float = 0.05, curvature: bool = True,
                  alpha_in: float = ALPHA_IN, min_error_df: int = MIN_ERROR_DF, transform: str = "auto") -> ResponseFit:
    """``fit_response`` on the runs that hold a value, with a smaller model where the full one cannot be fitted.

    ``transform``: "none", "log", or "auto" (doe.transform's Box-Cox choice, judged with the full model where
    the runs can fit it and with the estimable main effects where they cannot). Raises DoeError when not even
    the mean and one main effect can be estimated.
    """
    y = np.asarray(y, dtype=float).reshape(-1)
    if y.size != design.n_runs:
        raise DoeError(f"{response}: {y.size} values for {design.n_runs} runs")
    ok = np.isfinite(y)
    full = default_terms(design)
    X = model_matrix(design.coded[ok], full)
    whole = bool(ok.all() or (X.shape[0] >= X.shape[1] and rank(X) == X.shape[1]))
    choice = None
    if transform == "auto":
        judged_with = full if whole else estimable_mains(design.coded[ok], full, min_error_df)
        choice = choose_transform(design.coded[ok], y[ok], judged_with, alpha)
        transform = choice.transform
    if whole:
        fit = fit_response(design, y, response=response, alpha=alpha, curvature=curvature, transform=transform)
    else:
        z = np.full_like(y, np.nan)
        z[ok] = forward(y[ok], transform)  # the interactions are selected on the scale the model is fitted on
        kept, dropped = estimable_terms(design, z, full, alpha_in, min_error_df)
        if not kept:
            raise DoeError(f"{response}: the {int(ok.sum())} runs with a value cannot estimate any factor's "
                           f"effect ({int((~ok).sum())} of {design.n_runs} runs have none)")
        fit = ResponseFit(design, y, kept, response, alpha, curvature, transform)
        letters = design.letters
        fit.reduction_log = [
            f"{int((~ok).sum())} of {design.n_runs} runs have no value, and the rest cannot estimate the full "
            f"model ({len(full)} terms): kept {', '.join(term_label(t, letters) for t in kept)} (every estimable "
            f"main effect, interactions by forward selection with p <= {alpha_in:g}); not in the model: "
            f"{', '.join(term_label(t, letters) for t in dropped) or 'none'}"]
    if choice is not None and choice.transform != "none":
        fit.messages.append(choice.reason)
    return fit
