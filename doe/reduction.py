"""Hierarchy-preserving backward elimination of model terms.

method 'p' drops, one at a time, the term with the largest p-value above
alpha_out among terms no other term needs (AB keeps A and B; A^2 keeps A);
'lenth' (for unreplicated saturated fits) keeps the effects beyond Lenth's
margin of error plus their parents, so the dropped effects become the error
estimate: the thesis's "hidden replication" (Appendix A.4).
"""
from __future__ import annotations

from .factors import DoeError
from .terms import mask_to_term, parents


def reduce_fit(fit0, alpha_out: float = 0.10, method: str = "auto"):
    from .fit import ResponseFit

    if method == "auto":
        method = "p" if fit0.has_error else "lenth"
    if method == "lenth":
        if fit0.effects is None or fit0.effects.margin_of_error is None:
            raise DoeError("Lenth reduction needs the effects of a two-level factorial")
        keep = set()
        k = fit0.design.k
        for term in fit0.effects.significant():
            mask = next(c.mask for c in fit0.design.aliases.chains if c.term == term)
            t = mask_to_term(mask, k)
            keep |= {t, *parents(t)}
        keep &= set(fit0.terms) | {p for t in keep for p in parents(t)}
        fit = ResponseFit(fit0.design, fit0._y_full(), sorted(keep), fit0.response, fit0.alpha,
                          fit0.curvature_requested, fit0.transform)
        fit.reduction_log = [f"kept {', '.join(fit.term_labels) or 'the mean only'} (beyond Lenth ME "
                             f"{fit0.effects.margin_of_error:.4g} or needed by hierarchy)"]
        return fit
    if method != "p":
        raise DoeError("method must be 'auto', 'p' or 'lenth'")
    if not fit0.has_error:
        raise DoeError(f"{fit0.response}: no error estimate, so p-values cannot guide reduction; "
                       "use method='lenth'")
    fit, log = fit0, []
    while fit.terms:
        needed = {p for t in fit.terms for p in parents(t)}
        rows = {r.source: r for r in fit.anova}
        cands = [(rows[lbl].p_value, t, lbl) for t, lbl in zip(fit.terms, fit.term_labels)
                 if t not in needed and rows[lbl].p_value is not None]
        if not cands:
            break
        p_max, t_drop, lbl = max(cands, key=lambda c: c[0])
        if p_max <= alpha_out:
            break
        log.append(f"removed {lbl} (p = {p_max:.4g})")
        fit = ResponseFit(fit0.design, fit0._y_full(), [t for t in fit.terms if t != t_drop],
                          fit0.response, fit0.alpha, fit0.curvature_requested, fit0.transform)
    fit.reduction_log = log
    return fit

