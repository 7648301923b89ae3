"""The design view (calibration.design.design_view without its ``doe`` dict): the preview's answer,
an iteration's design, and a proposed next design."""
from __future__ import annotations

from pydantic import Field

from service.api.responses.common import Factor, Out


class AliasChain(Out):
    term: str = Field(description="an estimable term, e.g. 'A' or 'AB'")
    aliases: list[str] = Field(description="the words aliased with it, signed ('-BCD')")
    label: str = Field(description="e.g. 'A = BCD'")


class Aliases(Out):
    """The alias structure of a fractional design (doe.aliases)."""

    defining_relation: list[str] = Field(description="e.g. ['I = ABCD']; [] for a full factorial")
    resolution: int | None = Field(description="null: no aliasing (full factorial)")
    resolution_label: str
    chains: list[AliasChain]


class ReusedFrom(Out):
    """Which battery of an earlier iteration a design row reuses (calibration.reuse)."""

    iteration: int
    kind: str
    std_order: int
    seed: int
    job_id: int | None


class DesignBatteries(Out):
    run: int = Field(description="design rows run for this iteration")
    reused: int = Field(description="design rows that are batteries of earlier iterations")


class DesignRun(Out):
    std_order: int = Field(description="standard order, from 1")
    run_order: int = Field(description="randomised order the runs are queued in")
    point_type: str = Field(description="'factorial', 'center', 'axial', or 'other' (an earlier iteration's battery "
                                        "off the design's points, reused as a further point of the fit)")
    replicate: int
    seed: int | None = Field(description="the run's random seed")
    natural: dict[str, float] = Field(description="per factor: the level in its unit")
    coded: dict[str, float] = Field(description="per factor: the level coded to [-1, 1]")
    reused_from: ReusedFrom | None = Field(None, description="the earlier iteration's battery this row is (not run "
                                                             "again); null: run for this design")


class DesignView(Out):
    """A design table in natural and coded units with its alias structure and resolution."""

    kind: str = Field(description="e.g. '2^(4-1) fractional factorial'")
    factors: list[Factor]
    generators: list[str] = Field(description="generators of a fractional design, e.g. ['D=ABC']")
    n_runs: int
    resolution: int | None
    resolution_label: str | None
    aliases: Aliases | None
    runs: list[DesignRun]
    factor_names: list[str]
    notes: list[str]
    batteries: DesignBatteries | None = Field(None, description="an iteration's design: rows run and rows reused")
