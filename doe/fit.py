"""Least-squares model of one response over a design, with its ANOVA.

`fit_response` returns a `ResponseFit`, shaped like a statsmodels results object:
numbers as attributes, `.to_dict()` for the API, `.summary()` for people.

The ANOVA follows Design-Expert: partial sums of squares per term; when a
two-level design has centre runs and the model has no squared terms, a single-df
curvature row (factorial mean vs centre mean) is split off the residual; the
residual splits into lack of fit and pure error (replicated points, e.g. centre
runs with different seeds). A saturated model without replicates has no error
estimate: F and p are left as None and the fit says so, instead of printing the
meaningless numbers the thesis rightly refused to compute (Appendix A.2.2).
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import statsmodels.api as sm
from scipy import stats

from .designs import Design
from .effects import EffectsResult, compute_effects
from .factors import DoeError, coded_matrix
from .terms import (Term, mask_to_term, model_matrix, natural_transform, parents, parse_term,
                    sort_terms, term_label, term_name)
from .lstsq import rank, residual_ss
from .transform import TRANSFORMS, forward, inverse

NO_ERROR_MESSAGE = ("No error estimate: the model has as many coefficients as distinct runs and there are "
                    "no replicates, so F and p-values do not exist. Judge effects from the half-normal plot "
                    "and Lenth's PSE, or add centre runs / replicates.")


@dataclass
class AnovaRow:
    source: str
    sum_of_squares: float
    df: int
    mean_square: float | None = None
    f_value: float | None = None
    p_value: float | None = None

    def to_dict(self) -> dict:
        return {k: _clean(v) for k, v in self.__dict__.items()}


def _clean(v):
    if isinstance(v, (float, np.floating)):
        v = float(v)
        return v if math.isfinite(v) else None
    if isinstance(v, np.integer):
        return int(v)
    return v


def _sse(X: np.ndarray, y: np.ndarray) -> tuple[float, int]:
    return residual_ss(X, y), rank(X)


def default_terms(design: Design) -> list[Term]:
    """Main effects and estimable two-factor interactions; squares too if axial runs exist."""
    k = design.k
    if design.aliases is not None:
        terms = [mask_to_term(c.mask, k) for c in design.aliases.chains if bin(c.mask).count("1") <= 2]
    else:
        terms = [t for t in (mask_to_term(m, k) for m in range(1, 1 << k)) if sum(t) <= 2]
    if any(t == "axial" for t in design.point_type):
        terms += [tuple(2 if j == i else 0 for j in range(k)) for i in range(k)]
    return sort_terms(terms)


def pure_error(coded: np.ndarray, y: np.ndarray) -> tuple[float, int]:
    groups: dict[bytes, list[float]] = {}
    for row, v in zip(np.round(coded, 9), y):
        groups.setdefault(row.tobytes(), []).append(v)
    ss = sum(float(np.sum((np.array(g) - np.mean(g)) ** 2)) for g in groups.values())
    return ss, len(y) - len(groups)


class ResponseFit:
    """Fitted model of one response; build with `fit_response`."""

    def __init__(self, design: Design, y, terms=None, response: str = "y", alpha: float = 0.05,
                 curvature: bool = True, transform: str = "none"):
        y_all = np.asarray(y, dtype=float).reshape(-1)
        if y_all.size != design.n_runs:
            raise DoeError(f"{response}: {y_all.size} values for {design.n_runs} runs")
        if transform not in TRANSFORMS:
            raise DoeError(f"{response}: transform must be one of {', '.join(TRANSFORMS)}")
        if transform == "log" and not np.all(y_all[np.isfinite(y_all)] > 0):
            raise DoeError(f"{response}: a log transform needs every value positive")
        # the model, its ANOVA and its coefficients are on the transformed scale; predictions come back on y's
        self.transform = transform
        self.design, self.response, self.alpha = design, response, alpha
        self.curvature_requested = curvature
        self.messages: list[str] = []
        self.reduction_log: list[str] = []
        ok = np.isfinite(y_all)
        if not ok.all():
            self.messages.append(f"{int((~ok).sum())} run(s) without a value for {response} were left out.")
        self.used = ok
        self.coded, self.y_raw = design.coded[ok], y_all[ok]
        self.y = forward(self.y_raw, transform)
        if transform == "log":
            self.messages.append(f"Fitted to ln({response}): coefficients, ANOVA and effects are on that scale; "
                                 "predictions and their intervals are transformed back.")
        factors = design.factors
        letters = design.letters
        if terms is None:
            terms = default_terms(design)
        terms = sort_terms(parse_term(t, factors) if isinstance(t, str) else tuple(t) for t in terms)
        self.terms: list[Term] = terms
        self.term_labels = [term_label(t, letters) for t in terms]
        missing = {term_label(p, letters) for t in terms for p in parents(t)} - set(self.term_labels)
        if missing:
            self.messages.append("Model is not hierarchical; missing " + ", ".join(sorted(missing)) + ".")
        X = model_matrix(self.coded, terms)
        n, p = X.shape
        if n < p:
            raise DoeError(f"{response}: {p} coefficients cannot be fitted from {n} runs")
        if np.linalg.matrix_rank(X) < p:
            raise DoeError(f"{response}: model terms are aliased in this design "
                           f"({', '.join(self.term_labels)}); drop one term of each alias chain")
        self.X, self.n, self.p = X, n, p
        self.df_resid = n - p
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self.ols = sm.OLS(self.y, X).fit()
        self.params = np.asarray(self.ols.params, dtype=float)
        sse_m = float(np.sum((self.y - X @ self.params) ** 2))
        self._anova(curvature)
        # Error for tests and intervals: the ANOVA residual, i.e. with curvature taken
        # out when it has its own row (as Design-Expert does); otherwise the model residual.
        if self.curvature_row is not None:
            self.error_variance_df = self.error_df
            self.mse = self.error_mean_square
        else:
            self.error_variance_df = self.df_resid
            self.mse = sse_m / self.df_resid if self.df_resid > 0 else None
        self.has_error = self.error_variance_df > 0 and self.mse is not None
        if not self.has_error:
            self.mse = None
        self.cov = (np.asarray(self.ols.normalized_cov_params, dtype=float) * self.mse) if self.has_error else None
        if self.curvature_row is not None and self.has_error:
            self.messages.append("Standard errors and intervals use the residual with curvature removed; "
                                 "if curvature is significant the model is biased near the centre.")
        ss_tot = float(np.sum((self.y - self.y.mean()) ** 2))
        self.r_squared = 1 - sse_m / ss_tot if ss_tot > 0 else None
        self.adj_r_squared = (1 - (sse_m / self.df_resid) / (ss_tot / (n - 1))
                              if self.df_resid > 0 and ss_tot > 0 else None)
        h = np.einsum("ij,jk,ik->i", X, np.linalg.pinv(X.T @ X), X)
        if np.all(h < 1 - 1e-9):
            e = (self.y - X @ self.params) / (1 - h)
            self.press = float(e @ e)
            self.pred_r_squared = 1 - self.press / ss_tot if ss_tot > 0 else None
        else:
            self.press, self.pred_r_squared = None, None
        self.std_dev = math.sqrt(self.mse) if self.mse is not None else None
        self.mean = float(self.y.mean())
        monos, M = natural_transform(terms, factors)
        self.natural_names = [term_name(m, factors) for m in monos]
        self.natural_params = M @ self.params
        self.natural_std_errors = (np.sqrt(np.diag(M @ self.cov @ M.T)) if self.cov is not None else None)
        self.effects: EffectsResult | None = None
        fac = design.factorial_mask[ok]
        if fac.sum() >= 2 and design.aliases is not None:
            self.effects = compute_effects(self.coded, self.y, fac, design.aliases, response, alpha)
        if not self.has_error:
            self.messages.append(NO_ERROR_MESSAGE)

    # --- ANOVA -------------------------------------------------------------------
    def _anova(self, curvature: bool):
        X, y, n = self.X, self.y, self.n
        types = np.array(self.design.point_type)[self.used]
        quad = any(p > 1 for t in self.terms for p in t)
        use_curv = (curvature and not quad and (types == "center").any() and (types == "factorial").any()
                    and set(types) <= {"factorial", "center"})
        XF = np.column_stack([X, (types == "center").astype(float)]) if use_curv else X
        sse_full, rank_full = _sse(XF, y)
        df_res = n - rank_full
        if df_res == 0:
            sse_full = 0.0  # an exact fit; what lstsq leaves is round-off
        ms_e = sse_full / df_res if df_res > 0 else None

        def test(ss, df):
            if ms_e is None or df <= 0:
                return AnovaRow("", ss, df, ss / df if df > 0 else None)
            ms = ss / df
            f = ms / ms_e if ms_e > 0 else float("inf")
            return AnovaRow("", ss, df, ms, f, float(stats.f.sf(f, df, df_res)))

        rows = []
        base = XF[:, [0, XF.shape[1] - 1]] if use_curv else XF[:, :1]
        model_ss = _sse(base, y)[0] - sse_full
        r = test(model_ss, self.p - 1)
        r.source = "Model"
        rows.append(r)
        for j, label in enumerate(self.term_labels, start=1):
            ss = _sse(np.delete(XF, j, axis=1), y)[0] - sse_full
            r = test(max(ss, 0.0), 1)
            r.source = label
            rows.append(r)
        self.curvature_row = None
        if use_curv:
            ss_c = _sse(X, y)[0] - sse_full
            r = test(max(ss_c, 0.0), 1)
            r.source = "Curvature"
            rows.append(r)
            self.curvature_row = r
        rows.append(AnovaRow("Residual", sse_full, df_res, ms_e))
        ss_pe, df_pe = pure_error(self.coded, y)
        self.lack_of_fit_row = None
        if df_pe > 0 and df_res > 0:
            ss_lof, df_lof = max(sse_full - ss_pe, 0.0), df_res - df_pe
            ms_pe = ss_pe / df_pe
            if df_lof > 0:
                ms_lof = ss_lof / df_lof
                f = ms_lof / ms_pe if ms_pe > 0 else float("inf")
                self.lack_of_fit_row = AnovaRow("Lack of Fit", ss_lof, df_lof, ms_lof, f,
                                                float(stats.f.sf(f, df_lof, df_pe)))
                rows.append(self.lack_of_fit_row)
            rows.append(AnovaRow("Pure Error", ss_pe, df_pe, ms_pe))
        rows.append(AnovaRow("Cor Total", float(np.sum((y - y.mean()) ** 2)), n - 1))
        self.anova = rows
        self.error_mean_square = ms_e
        self.error_df = df_res

    # --- access ------------------------------------------------------------------
    def anova_row(self, source: str) -> AnovaRow:
        for r in self.anova:
            if r.source == source:
                return r
        raise KeyError(source)

    @property
    def coefficients(self) -> dict[str, float]:
        """Coded-unit coefficients keyed by 'Intercept', 'A', 'AB', ..."""
        return dict(zip(["Intercept"] + self.term_labels, map(float, self.params)))

    @property
    def natural_coefficients(self) -> dict[str, float]:
        """Natural-unit coefficients keyed by 'const', 'rho_p', 'rho_p*mu_pp', ..."""
        return dict(zip(self.natural_names, map(float, self.natural_params)))

    def _coef_rows(self) -> list[dict]:
        rows = []
        t_crit = stats.t.ppf(1 - self.alpha / 2, self.error_variance_df) if self.has_error else None
        for i, label in enumerate(["Intercept"] + self.term_labels):
            d = {"term": label, "name": term_name(self.terms[i - 1], self.design.factors) if i else "const",
                 "estimate": float(self.params[i]), "std_error": None, "t_value": None, "p_value": None,
                 "ci_low": None, "ci_high": None}
            if self.has_error:
                se = float(np.sqrt(self.cov[i, i]))
                d.update(std_error=se, ci_low=self.params[i] - t_crit * se, ci_high=self.params[i] + t_crit * se)
                if se > 0:
                    t = self.params[i] / se
                    d.update(t_value=t, p_value=float(2 * stats.t.sf(abs(t), self.error_variance_df)))
            rows.append({k: _clean(v) for k, v in d.items()})
        return rows

    def _rows_coded(self, points) -> np.ndarray:
        if isinstance(points, dict):
            points = [points]
        return coded_matrix(self.design.factors, points, row_label="prediction point")

    def predict_coded(self, coded: np.ndarray) -> np.ndarray:
        return inverse(model_matrix(coded, self.terms) @ self.params, self.transform)

    def predict(self, points, alpha: float | None = None, n_future: int = 1) -> list[dict]:
        """Mean prediction with confidence and prediction intervals at natural-unit points.

        The prediction interval is for the mean of ``n_future`` new runs at a point (variance
        se^2 + MSE / n_future, the regression textbooks' interval for a future mean): a confirmation
        averaged over several seeds is judged against the interval of an average. On a log scale the mean
        and the interval bounds are transformed back (the mean is then the median of y's distribution) and
        ``se_mean`` is the delta method's, exp(m) times the standard error of m."""
        if n_future < 1:
            raise DoeError("n_future must be at least 1")
        alpha = self.alpha if alpha is None else alpha
        Xp = model_matrix(self._rows_coded(points), self.terms)
        mean = Xp @ self.params
        out = []
        t_crit = stats.t.ppf(1 - alpha / 2, self.error_variance_df) if self.has_error else None
        for i in range(len(mean)):
            back = float(inverse(mean[i], self.transform))
            d = {"response": self.response, "mean": back, "se_mean": None, "ci_low": None,
                 "ci_high": None, "pi_low": None, "pi_high": None, "alpha": alpha}
            if self.has_error:
                se = float(np.sqrt(Xp[i] @ self.cov @ Xp[i]))
                sp = math.sqrt(se**2 + self.mse / n_future)
                b = {k: float(inverse(v, self.transform)) for k, v in (
                    ("ci_low", mean[i] - t_crit * se), ("ci_high", mean[i] + t_crit * se),
                    ("pi_low", mean[i] - t_crit * sp), ("pi_high", mean[i] + t_crit * sp))}
                d.update(se_mean=se * back if self.transform == "log" else se, **b)
            out.append({k: _clean(v) for k, v in d.items()})
        return out

    def equation(self, natural: bool = True, digits: int = 6) -> str:
        names = self.natural_names if natural else ["1"] + self.term_labels
        vals = self.natural_params if natural else self.params
        parts = [f"{vals[0]:.{digits}g}"]
        for nme, v in zip(names[1:], vals[1:]):
            parts.append(f"{'-' if v < 0 else '+'} {abs(v):.{digits}g} * {nme}")
        lhs = f"ln({self.response})" if self.transform == "log" else self.response
        return f"{lhs} = " + " ".join(parts)

    # --- model reduction -----------------------------------------------------------
    def reduce(self, alpha_out: float = 0.10, method: str = "auto") -> "ResponseFit":
        """Hierarchy-preserving backward elimination; see doe.reduction.reduce_fit."""
        from .reduction import reduce_fit
        return reduce_fit(self, alpha_out, method)

    def _y_full(self) -> np.ndarray:
        """The responses as given (untransformed), NaN where a run had none: what a refit starts from."""
        y = np.full(self.design.n_runs, np.nan)
        y[self.used] = self.y_raw
        return y

    # --- output --------------------------------------------------------------------
    def fit_statistics(self) -> dict:
        cv = 100 * self.std_dev / abs(self.mean) if self.std_dev is not None and self.mean else None
        return {k: _clean(v) for k, v in {
            "n_runs": self.n, "n_coefficients": self.p, "df_residual": self.df_resid,
            "std_dev": self.std_dev, "mean": self.mean, "cv_percent": cv, "r_squared": self.r_squared,
            "adj_r_squared": self.adj_r_squared, "pred_r_squared": self.pred_r_squared,
            "press": self.press}.items()}

    def to_dict(self) -> dict:
        nat = [{"name": nme, "estimate": float(v),
                "std_error": _clean(self.natural_std_errors[i]) if self.natural_std_errors is not None else None}
               for i, (nme, v) in enumerate(zip(self.natural_names, self.natural_params))]
        return {"response": self.response, "transform": self.transform, "terms": list(self.term_labels),
                "factors": [f.to_dict() for f in self.design.factors],
                "coefficients_coded": self._coef_rows(), "coefficients_natural": nat,
                "equation_coded": self.equation(natural=False), "equation_natural": self.equation(),
                "anova": [r.to_dict() for r in self.anova], "has_error_estimate": self.has_error,
                "fit_statistics": self.fit_statistics(),
                "effects": self.effects.to_dict() if self.effects else None,
                "messages": list(self.messages), "reduction_log": list(self.reduction_log)}

    def summary(self) -> str:
        from .report import fmt, fmt_p, table
        parts = [f"Response: {self.response}   model: {', '.join(self.term_labels) or 'mean only'}"]
        if self.effects is not None:
            parts.append(self.effects.summary())
        parts.append(table(["Source", "Sum sq", "df", "Mean sq", "F", "p"],
                           [[r.source, r.sum_of_squares, str(r.df), r.mean_square, r.f_value, fmt_p(r.p_value)]
                            for r in self.anova], "ANOVA (partial sums of squares)"))
        st = self.fit_statistics()
        parts.append("  ".join(f"{k} {fmt(v)}" for k, v in st.items()))
        parts.append(table(["Term", "Coded coef", "Std err", "t", "p", "CI low", "CI high"],
                           [[r["term"], r["estimate"], r["std_error"], r["t_value"], fmt_p(r["p_value"]),
                             r["ci_low"], r["ci_high"]] for r in self._coef_rows()], "Coefficients, coded units"))
        parts.append(table(["Term", "Natural coef"], [[nme, float(v)] for nme, v in
                                                      zip(self.natural_names, self.natural_params)],
                           "Coefficients, natural units"))
        parts.append(self.equation())
        parts += self.messages + self.reduction_log
        return "\n\n".join(parts)


def fit_response(design: Design, y, terms=None, response: str = "y", alpha: float = 0.05,
                 curvature: bool = True, transform: str = "none") -> ResponseFit:
    """Fit one response; `y` is aligned with the design's rows (standard order); ``transform`` "log" fits
    ln(y) (doe.transform says when that is the better scale)."""
    return ResponseFit(design, y, terms, response, alpha, curvature, transform)


def fit_responses(design: Design, results: list[dict], responses=None, terms=None,
                  alpha: float = 0.05) -> dict[str, ResponseFit]:
    """Fit every response in `results` (one dict per design row, standard order)."""
    if len(results) != design.n_runs:
        raise DoeError(f"{len(results)} result rows for {design.n_runs} runs")
    if responses is None:
        responses = sorted({k for r in results for k in r})
    fits = {}
    for name in responses:
        y = []
        for i, r in enumerate(results):
            v = r.get(name)
            try:
                y.append(float("nan") if v is None else float(v))
            except (TypeError, ValueError):
                raise DoeError(f"run {i + 1}: {name} = {v!r} is not a number") from None
        t = terms.get(name) if isinstance(terms, dict) else terms
        fits[name] = ResponseFit(design, y, t, name, alpha)
    return fits
