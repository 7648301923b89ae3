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


class DesignRun(Out):
    std_order: int = Field(description="standard order, from 1")
    run_order: int = Field(description="randomised order the runs are queued in")
    point_type: str = Field(description="'factorial', 'centre' or 'axial'")
    replicate: int
    seed: int | None = Field(description="the run's random seed")
    natural: dict[str, float] = Field(description="per factor: the level in its unit")
    coded: dict[str, float] = Field(description="per factor: the level coded to [-1, 1]")


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
