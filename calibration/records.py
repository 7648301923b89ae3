"""Plain records the calibration loop works on: measured targets and the noise behind them.

No database here: the service builds these from its rows (``Measured.from_record`` reads any
object or dict with test/quantity/condition/values), a notebook builds them by hand.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping

from .keys import ResponseKey


@dataclass(frozen=True)
class Measured:
    """One measured bulk value: its key, replicate values (SI) and what is known of its scatter.

    ``stated_uncertainty`` is the standard uncertainty of the mean when a source published one
    (then it wins over the replicates' scatter, as in the service's measurement store). ``input_unit``, the
    unit the values were typed in, lets a report's plausibility warning name the likely unit slip.
    """

    key: ResponseKey
    values: tuple[float, ...]
    unit: str = ""
    stated_uncertainty: float | None = None
    id: int | None = None
    input_unit: str = ""

    def __post_init__(self):
        if not self.values:
            raise ValueError(f"{self.key.label}: a measurement needs at least one value")
        if not all(math.isfinite(v) for v in self.values):
            raise ValueError(f"{self.key.label}: values must be finite")

    @classmethod
    def from_record(cls, record: Any) -> "Measured":
        get = record.get if isinstance(record, Mapping) else lambda k, d=None: getattr(record, k, d)
        stated = get("stated_uncertainty", None)
        if stated is None and isinstance(record, Mapping):
            stated = record.get("standard_uncertainty") if len(record.get("values", ())) < 2 else None
        return cls(ResponseKey.from_record(record), tuple(float(v) for v in get("values")),
                   str(get("unit", "") or ""), None if stated is None else float(stated), get("id", None),
                   str(get("input_unit", "") or ""))

    @property
    def n(self) -> int:
        return len(self.values)

    @property
    def mean(self) -> float:
        return math.fsum(self.values) / self.n

    @property
    def sd(self) -> float | None:
        """Replicate standard deviation (n - 1 in the denominator); None below two replicates."""
        if self.n < 2:
            return None
        m = self.mean
        return math.sqrt(math.fsum((v - m) ** 2 for v in self.values) / (self.n - 1))

    def mean_variance(self, default_relative: float) -> "VarianceTerm":
        """Variance of the mean, with its degrees of freedom and whether it was assumed.

        Replicates give s^2/n on n - 1 degrees of freedom; a stated uncertainty is taken as known
        (infinite df); with neither, ``default_relative`` x |mean| is assumed and flagged.
        """
        if self.stated_uncertainty is not None and self.stated_uncertainty > 0:
            return VarianceTerm(self.stated_uncertainty**2, math.inf, "stated")
        sd = self.sd
        if sd is not None and sd > 0:
            return VarianceTerm(sd**2 / self.n, self.n - 1, "replicates")
        u = default_relative * abs(self.mean)
        if u <= 0:
            raise ValueError(f"{self.key.label}: no replicates, no stated uncertainty and a zero mean; "
                             "give an uncertainty")
        return VarianceTerm(u * u, math.inf, "assumed")


@dataclass(frozen=True)
class VarianceTerm:
    """One component of a target's noise: a variance, its degrees of freedom, where it came from."""

    variance: float
    df: float
    source: str


@dataclass(frozen=True)
class Noise:
    """Full noise of one standardised residual (design note 2.1): v = s_meas^2/n + s_sim^2/m + v_emul.

    ``df`` is Satterthwaite's effective degrees of freedom of the sum, so that a residual whitened
    with estimated variances can be referred to a t (not a normal) distribution.
    """

    measurement: VarianceTerm
    simulator: VarianceTerm
    emulator: VarianceTerm = field(default_factory=lambda: VarianceTerm(0.0, math.inf, "none"))

    @property
    def variance(self) -> float:
        return self.measurement.variance + self.simulator.variance + self.emulator.variance

    @property
    def sd(self) -> float:
        return math.sqrt(self.variance)

    @property
    def df(self) -> float:
        terms = [t for t in (self.measurement, self.simulator, self.emulator) if t.variance > 0]
        denom = sum(t.variance**2 / t.df for t in terms if math.isfinite(t.df) and t.df > 0)
        if denom == 0:
            return math.inf
        return self.variance**2 / denom

    def to_dict(self) -> dict:
        return {"measurement_variance": self.measurement.variance, "measurement_df": _df(self.measurement.df),
                "measurement_source": self.measurement.source,
                "simulator_variance": self.simulator.variance, "simulator_df": _df(self.simulator.df),
                "emulator_variance": self.emulator.variance, "total_sd": self.sd, "df": _df(self.df)}


def _df(df: float) -> float | None:
    return None if math.isinf(df) else float(df)


def _relative(measured: Measured) -> bool:
    """Scatter that scales with the value (densities, moduli, stresses, forces) or not (angles)."""
    return measured.unit != "deg" and not measured.key.quantity.endswith("_deg")


def measurement_variances(targets: list[Measured], default_relative: float) -> dict:
    """Variance of each target's mean, pooling replicate scatter within a (test, quantity) family.

    Why pool: three replicates give a variance on 2 degrees of freedom, so a residual whitened by
    it has t_2 tails and no test can see a real misfit through them. The conditions of one family
    (E' at four stresses, shear stress at four loads) share a coefficient of variation (an
    absolute scatter for angles), so their replicates are pooled (one-way ANOVA within groups):
    s_pooled^2 = sum (n_i - 1) s_i^2 / sum (n_i - 1), with that many degrees of freedom. Stated
    uncertainties stay as stated; targets without replicates take the pooled value of their family
    when there is one, else the assumed ``default_relative``.
    """
    families: dict[tuple[str, str], list[Measured]] = {}
    for t in targets:
        families.setdefault((t.key.test, t.key.quantity), []).append(t)
    out = {}
    for members in families.values():
        ss, df = 0.0, 0
        for t in members:
            sd = t.sd
            if t.stated_uncertainty is None and sd is not None and sd > 0:
                scale = abs(t.mean) if _relative(t) else 1.0
                if scale > 0:
                    ss += (t.n - 1) * (sd / scale) ** 2
                    df += t.n - 1
        for t in members:
            if t.stated_uncertainty is not None and t.stated_uncertainty > 0:
                out[t.key] = t.mean_variance(default_relative)
            elif df > 0 and (len(members) > 1 or t.n > 1):
                scale = abs(t.mean) if _relative(t) else 1.0
                out[t.key] = VarianceTerm(ss / df * scale**2 / t.n, df,
                                          "replicates pooled over conditions" if len(members) > 1 else "replicates")
            else:
                out[t.key] = t.mean_variance(default_relative)
    return out
