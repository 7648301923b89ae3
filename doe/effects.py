"""Effects of a two-level factorial, with Lenth's pseudo standard error.

An effect is mean(y at +1) - mean(y at -1) over the factorial runs (Eq. A.1 of
the thesis); centre and axial runs do not enter. With no replicates there is no
error estimate, so significance is judged from the effects themselves: Lenth's
PSE (Technometrics 31, 1989) is a robust scale estimate from the small effects,
which under effect sparsity are noise. The half-normal and Pareto data are what
Design-Expert plots.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from .aliases import AliasStructure, word_column
from .report import fmt, table


@dataclass
class Effect:
    term: str
    alias_label: str
    effect: float
    coefficient: float
    sum_of_squares: float
    percent_contribution: float

    def to_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass
class EffectsResult:
    response: str
    effects: list[Effect]
    n_factorial_runs: int
    lenth_pse: float | None = None
    margin_of_error: float | None = None            # t(0.975, m/3) * PSE
    simultaneous_margin_of_error: float | None = None
    lenth_df: float | None = None
    half_normal: list[dict] = field(default_factory=list)
    pareto: list[dict] = field(default_factory=list)
    messages: list[str] = field(default_factory=list)

    def __getitem__(self, term: str) -> float:
        for e in self.effects:
            if e.term == term:
                return e.effect
        raise KeyError(term)

    def as_dict(self) -> dict[str, float]:
        return {e.term: e.effect for e in self.effects}

    def significant(self, simultaneous: bool = False) -> list[str]:
        """Terms whose |effect| exceeds Lenth's (simultaneous) margin of error."""
        lim = self.simultaneous_margin_of_error if simultaneous else self.margin_of_error
        if lim is None:
            return []
        return [e.term for e in self.effects if abs(e.effect) > lim]

    def to_dict(self) -> dict:
        return {"response": self.response, "n_factorial_runs": self.n_factorial_runs,
                "effects": [e.to_dict() for e in self.effects], "lenth_pse": self.lenth_pse,
                "margin_of_error": self.margin_of_error,
                "simultaneous_margin_of_error": self.simultaneous_margin_of_error,
                "lenth_df": self.lenth_df, "half_normal": self.half_normal, "pareto": self.pareto,
                "messages": list(self.messages)}

    def summary(self) -> str:
        rows = [[e.term, e.alias_label, e.effect, e.coefficient, e.sum_of_squares,
                 f"{e.percent_contribution:.2f}"] for e in self.effects]
        out = [table(["Term", "Aliases", "Effect", "Coefficient", "Sum sq", "% contrib"], rows,
                     f"Effects on {self.response} ({self.n_factorial_runs} factorial runs)")]
        if self.lenth_pse is not None:
            out.append(f"Lenth PSE {fmt(self.lenth_pse)}, margin of error {fmt(self.margin_of_error)}, "
                       f"simultaneous margin {fmt(self.simultaneous_margin_of_error)} (df {self.lenth_df:.3g})")
        out += self.messages
        return "\n".join(out)


def lenth(effects: np.ndarray, alpha: float = 0.05) -> tuple[float, float, float, float]:
    """(PSE, ME, SME, df) for a vector of effects."""
    a = np.abs(np.asarray(effects, dtype=float))
    m = a.size
    s0 = 1.5 * np.median(a)
    small = a[a < 2.5 * s0]
    pse = 1.5 * np.median(small) if small.size else 0.0
    d = m / 3.0
    me = stats.t.ppf(1 - alpha / 2, d) * pse
    gamma = (1 + (1 - alpha) ** (1.0 / m)) / 2
    sme = stats.t.ppf(gamma, d) * pse
    return float(pse), float(me), float(sme), float(d)


def compute_effects(coded: np.ndarray, y: np.ndarray, factorial_mask: np.ndarray,
                    aliases: AliasStructure, response: str = "y", alpha: float = 0.05) -> EffectsResult:
    fac = np.asarray(factorial_mask, dtype=bool)
    X, yf = np.asarray(coded, dtype=float)[fac], np.asarray(y, dtype=float)[fac]
    n = yf.size
    ss_total = float(np.sum((yf - yf.mean()) ** 2))
    effects = []
    for chain in aliases.chains:
        col = word_column(X, chain.mask)
        eff = float(yf[col > 0].mean() - yf[col < 0].mean())
        ss = float((col @ yf) ** 2 / n)
        pct = 100.0 * ss / ss_total if ss_total > 0 else 0.0
        effects.append(Effect(chain.term, chain.label, eff, eff / 2.0, ss, pct))
    res = EffectsResult(response, effects, n)
    m = len(effects)
    if m < 3:
        res.messages.append("Too few effects for Lenth's PSE.")
        return res
    values = np.array([e.effect for e in effects])
    pse, me, sme, d = lenth(values, alpha)
    res.lenth_pse, res.margin_of_error, res.simultaneous_margin_of_error, res.lenth_df = pse, me, sme, d
    order = np.argsort(np.abs(values), kind="stable")
    for rank, i in enumerate(order, start=1):
        q = stats.norm.ppf(0.5 + 0.5 * (rank - 0.5) / m)
        res.half_normal.append({"term": effects[i].term, "abs_effect": abs(values[i]),
                                "half_normal_quantile": float(q), "sign": int(np.sign(values[i]))})
    t_lim = stats.t.ppf(1 - alpha / 2, d)
    bonf = stats.t.ppf(1 - alpha / (2 * m), d)
    for i in order[::-1]:
        t_val = abs(values[i]) / pse if pse > 0 else float("inf")
        res.pareto.append({"term": effects[i].term, "t_value": float(t_val), "t_limit": float(t_lim),
                           "bonferroni_limit": float(bonf), "sign": int(np.sign(values[i]))})
    if pse == 0:
        res.messages.append("Lenth's PSE is zero: most effects are exactly zero.")
    return res
