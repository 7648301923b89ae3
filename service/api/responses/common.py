"""What every response model shares: the base class, the route options that keep stored JSON as stored,
and the small records several areas reuse (a factor, a condition, the lack of fit).

Why ``exclude_unset``: the campaign's products are dicts stored as JSON whose rows carry only the keys
that apply (a target that was not simulated has no ``confirmed``); the page tells an absent key from a
null one. Validated into these models and written back with ``exclude_unset``, a response keeps
exactly the keys it had, and the models still document every key it can have.
"""
from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field


class Out(BaseModel):
    """Base of the response models. Keys such as ``model_slope`` are the products' own names, so pydantic's
    reserved ``model_`` prefix is not reserved here."""

    model_config = ConfigDict(protected_namespaces=())


def typed(model: Any) -> dict[str, Any]:
    """Route keyword arguments for a response built as a dict: its model, and absent keys kept absent."""
    return {"response_model": model, "response_model_exclude_unset": True}


class Page(Out):
    """What every listing answers besides its items: the total matching the filters (on every page), and
    the limit and offset this page was cut with. The next page starts at ``offset + limit`` while it is
    below ``total``."""

    total: int = Field(description="rows matching the filters, whatever the page")
    limit: int = Field(description="rows per page asked for")
    offset: int = Field(description="rows skipped before this page")


Condition = dict[str, float]
CONDITION = "the test condition, SI, e.g. {'normal_stress_pa': 24000.0}; {} when the test has none"
ParameterValues = dict[str, float | None]
PARAMETERS = "per factor path (e.g. 'friction_pp', 'effects.rolling_epsd2.rolling_friction'): the value in its unit"


class Factor(Out):
    """One factor of a design: a micro-parameter path and the range it is varied over."""

    name: str = Field(description="micro-parameter path, e.g. 'particle_stiffness_n_per_m'")
    letter: str | None = Field(None, description="the design's letter for it (A, B, ...)")
    low: float = Field(description="low level, in the factor's unit")
    high: float = Field(description="high level, in the factor's unit")
    unit: str = Field("", description="the factor's unit")
    log: bool = Field(False, description="varied on a log scale")


class LackOfFit(Out):
    """The omnibus test of the model against the measurements (calibration.stats.lack_of_fit)."""

    statistic: float | None = Field(None, description="chi2: sum of squared standardised residuals")
    dof: int | None = Field(None, description="degrees of freedom: residuals minus free parameters")
    p_value: float | None = Field(None, description="P(chi2 >= statistic) under the model; null without dof")
    n_residuals: int | None = Field(None, description="standardised residuals summed (targets and priors)")
    chi2_per_dof: float | None = Field(None, description="statistic / dof")
    noise_band: list[float | None] | None = Field(
        None, description="[low, high]: where chi2 / dof lies by chance (1 -+ 2 sqrt(2 / dof))")


class CostEstimate(Out):
    """What a job (a campaign: each of its batteries) costs where it runs, shown when it is created
    (engine.lab.cost.estimate_view): ceilings from the procedures' own stop rules, not guesses."""

    rig: str = Field(description="the rig the batteries run in")
    resolution: str = Field(description="'thesis' or 'screening' (presets), 'as_measured' or 'coarse'")
    scale_factor: float = Field(description="particle sizes over the material's (1: as measured)")
    contact_law: str = Field("linear", description="the contact effects that set the time step, e.g. "
                             "'hertz_mindlin' ('linear': none); the wall time is read off jobs of the same law")
    particles: int = Field(description="spheres of the largest packing")
    particles_stage: str | None = Field(None, description="the test that builds it")
    simulated_time_s: float = Field(description="simulated time of one battery, at most")
    stages_s: dict[str, float] = Field(default_factory=dict, description="simulated time per test, at most")
    batteries: int | None = Field(None, description="campaigns: the batteries of the first design")
    wall_time_s: float | None = Field(
        None, description="one battery's wall time on this service: the median over its latest finished jobs of wall "
                          "s / (particles x simulated s), times this job's (service.wall_estimate); null without a record")
    wall_time_range_s: list[float] | None = Field(
        None, description="[low, high]: the same with the smallest and the largest of those jobs' ratios")
    wall_time_basis: str | None = Field(None, description="which finished jobs the wall time rests on")
