"""Model-form discrepancy: what the model misses that no parameter and no candidate effect is meant to fix.

Every real material differs from any DEM model in small ways that are no physical effect: the test
procedure, the wall model, the size spread, the servo. Measured at identical micro parameters, demcal's
screening battery and the same battery in LIGGGHTS 3.8.0 agree on bulk density within 0.7 % but not on E'
(12 % apart) or the residual shear stress (8-34 %). A loop whose noise model holds only the measurement's and
the simulator's scatter reads such a mismatch as a missing effect, and calibrates its parameters to absorb it
with intervals too narrow (Brynjarsdottir & O'Hagan 2014). Following Kennedy & O'Hagan (2001), the
measurement y = f(theta) + delta + e carries a discrepancy delta per test, here a zero-mean term of stated
size: its variance adds to each target's noise, so it enters the lack of fit, the optimum's weights, the
diagnosis (signatures and residuals are whitened by the total sd) and the intervals at once.

Its size comes from evidence, one entry per test (optionally per quantity): a user's value, or
``from_comparison``: two models' runs of the same test at the same parameters (another engine, another
resolution), whose relative differences give an estimate with as many degrees of freedom as compared values.
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from pydantic import BaseModel, Field, model_validator

from calibration.keys import ResponseKey
from calibration.records import VarianceTerm
from engine.lab.registry import tests as lab_tests
from engine.lab.spec import STRICT_INPUT

MAX_SOURCE_CHARS = 2_000


class Discrepancy(BaseModel):
    """The size of one test's model-form discrepancy (one sd of delta), relative to the value or absolute in
    the quantity's SI unit; ``quantity`` None covers every quantity of the test."""

    model_config = STRICT_INPUT

    test: str = Field(..., max_length=32, description="lab test (GET /api/v1/tests)")
    quantity: str | None = Field(None, max_length=64, description="one of the test's quantities; none: all of them")
    relative_sd: float = Field(0.0, ge=0.0, le=1.0, description="sd of delta as a fraction of the value")
    absolute_sd: float = Field(0.0, ge=0.0, description="sd of delta in the quantity's SI unit (angles in deg)")
    df: float | None = Field(None, gt=0.0, description="degrees of freedom of the estimate; none: known exactly")
    source: str = Field("", max_length=MAX_SOURCE_CHARS, description="the evidence for the size")

    @model_validator(mode="after")
    def _known(self) -> "Discrepancy":
        registry = lab_tests()
        if self.test not in registry:
            raise ValueError(f"test {self.test!r} is not a lab test: one of {sorted(registry)}")
        names = [q.name for q in registry[self.test].quantities]
        if self.quantity is not None and self.quantity not in names:
            raise ValueError(f"quantity {self.quantity!r} is not one of test {self.test!r}'s: {names}")
        if self.relative_sd == 0.0 and self.absolute_sd == 0.0:
            raise ValueError("give relative_sd or absolute_sd (a discrepancy of zero is no entry)")
        return self

    def covers(self, key: ResponseKey) -> bool:
        return key.test == self.test and (self.quantity is None or self.quantity == key.quantity)

    def term(self, value: float) -> VarianceTerm:
        variance = (self.relative_sd * abs(value)) ** 2 + self.absolute_sd**2
        return VarianceTerm(variance, math.inf if self.df is None else self.df,
                            "model-form discrepancy" + (f" ({self.source})" if self.source else ""))


def discrepancy_term(key: ResponseKey, value: float, entries: Sequence[Discrepancy]) -> VarianceTerm | None:
    """The discrepancy of one target: the most specific entry (its quantity's over its test's), or None."""
    matching = [d for d in entries if d.covers(key)]
    if not matching:
        return None
    return sorted(matching, key=lambda d: d.quantity is None)[0].term(value)


def combined(measurement: VarianceTerm, discrepancy: VarianceTerm | None) -> VarianceTerm:
    """The measurement's variance plus the discrepancy's, with Satterthwaite's degrees of freedom."""
    if discrepancy is None or discrepancy.variance <= 0:
        return measurement
    total = measurement.variance + discrepancy.variance
    denom = sum(t.variance**2 / t.df for t in (measurement, discrepancy)
                if t.variance > 0 and math.isfinite(t.df) and t.df > 0)
    return VarianceTerm(total, math.inf if denom == 0 else total**2 / denom,
                        f"{measurement.source} + {discrepancy.source}")


def with_discrepancy(variances: Mapping[ResponseKey, VarianceTerm], means: Mapping[ResponseKey, float],
                     entries: Sequence[Discrepancy]) -> dict[ResponseKey, VarianceTerm]:
    """Each target's variance with its test's discrepancy added (unchanged where no entry covers it)."""
    if not entries:
        return dict(variances)
    return {key: combined(var, discrepancy_term(key, means[key], entries)) for key, var in variances.items()}


def _scales(quantity: str) -> bool:
    """A difference relative to the value (densities, moduli, stresses, forces) or absolute (angles, whose
    scatter does not grow with the angle and which can sit near zero: dilatancy)."""
    return not quantity.endswith("_deg")


def from_comparison(ours: Mapping[ResponseKey, float], theirs: Mapping[ResponseKey, float], *,
                    source: str = "") -> list[Discrepancy]:
    """Discrepancy entries, one per (test, quantity), from two models' values of the same tests.

    Each compared value gives one difference d_i (relative to the mean of the two; absolute for angles); the
    estimate is the root mean square sqrt(sum d_i^2 / n) with n degrees of freedom: the differences are
    taken as draws of a zero-mean delta, as Kennedy & O'Hagan's prior for it has them, not as a bias to
    correct (a systematic shift is part of what the term admits)."""
    groups: dict[tuple[str, str], list[float]] = {}
    for key, a in ours.items():
        if key not in theirs:
            continue
        b = theirs[key]
        if _scales(key.quantity):
            scale = 0.5 * (abs(a) + abs(b))
            if scale <= 0:
                continue
            d = (a - b) / scale
        else:
            d = a - b
        groups.setdefault((key.test, key.quantity), []).append(d)
    out = []
    for (test, quantity), diffs in sorted(groups.items()):
        size = math.sqrt(sum(d * d for d in diffs) / len(diffs))
        if size <= 0:
            continue
        what = {"relative_sd": min(size, 1.0)} if _scales(quantity) else {"absolute_sd": size}
        out.append(Discrepancy(test=test, quantity=quantity, df=float(len(diffs)),
                               source=source or f"comparison of {len(diffs)} values", **what))
    return out
