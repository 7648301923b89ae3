"""Rigs as data: the apparatus a measurement was made in, one section per test kind (SI, validated).

Why: a measurement means something only in the apparatus it was made in (a bulk mass is the mass of
*that* container's packing; a friction angle from a box ten particles wide is not one from a box four
wide). The thesis designed its 590 mm shear box for its material (chapter 3); another user measured in
a 300 mm box. A ``Rig`` records the apparatus; the engine builds its walls, loads and speeds from it
(``engine.lab.presets`` reads the bundled records, ``rig_records/*.json``), and the service stores users'.

Sections (each test kind reads its own):

* ``shear_box``: the split cylinder of the direct shear and confined compression tests: diameter, each
  half's height, the gap between the halves, the lid's start above the packing, the loads (stresses, or
  forces that are turned into stresses over the container area, as Appendix A gave them) and the range of
  the loading system, and the lab speeds;
* ``fill``: how the container is filled: the level the packing is struck off at and the free fall of the
  poured particles;
* ``angle_of_repose``: the bottomless bucket lifted off a floor (section 5.2), its frictions and speed;
* ``anchor``: the pull-out bin and the anchor (tube and foot plate), section 5.3.

What needs the particles is checked once they are known (``check_for_particles``): a gap a particle
falls through is refused; a box narrower than 10 of the largest particles, or a specimen thinner than 6, is
accepted with a warning (the sizes direct-shear standards ask for: ASTM D3080's 10 and 6 times the maximum
particle size, the thickness being the whole specimen's).
"""
from __future__ import annotations

import json
import math
from functools import lru_cache
from pathlib import Path
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator, model_validator

from engine.lab.errors import SpecFieldError
from engine.lab.whole_number import WholeNumber
from engine.particles.description import Particles

_MODEL = ConfigDict(extra="forbid", allow_inf_nan=False, strict=True, frozen=True)
# ceilings well above any laboratory (a 100 m apparatus, 100 m/s), so that a typo is refused while the cost
# model (engine.lab.cost), not these, decides what is too big to simulate
_MAX_LENGTH_M = 100.0
_MIN_SPEED_M_S, _MAX_SPEED_M_S = 1e-6, 100.0
_MAX_FORCE_N = 1e9
_MAX_STRESS_PA = 1.22e12  # diamond's modulus (engine.lab.bounds.STIFFEST_SOLID_PA)
_MAX_FRICTION = 10.0  # engine.lab.bounds.MAX_FRICTION_COEFFICIENT
_MAX_LOADS = 20
_MAX_CYCLES = 1000

Length = Annotated[float, Field(gt=0, le=_MAX_LENGTH_M)]
Speed = Annotated[float, Field(ge=_MIN_SPEED_M_S, le=_MAX_SPEED_M_S)]
Friction = Annotated[float, Field(ge=0, le=_MAX_FRICTION)]

# the direct-shear standards' sizes (ASTM D3080: specimen width >= 10, initial specimen thickness >= 6 maximum
# particle sizes). The thickness is the whole specimen's, both halves: a rule per half would flag the thesis's
# own box (165 mm halves, 42 mm largest particles), which its author designed for that material.
MIN_DIAMETER_PER_PARTICLE = 10.0
MIN_THICKNESS_PER_PARTICLE = 6.0

RECORDS_DIR = Path(__file__).with_name("rig_records")


class ShearBox(BaseModel):
    """Split cylindrical container of the DST and the CCT (thesis chapter 3; Appendix A Table A.7)."""

    model_config = _MODEL
    container_diameter_m: Length
    bottom_half_height_m: Length
    top_half_height_m: Length
    gap_m: float = Field(..., ge=0, le=_MAX_LENGTH_M, description="gap between the halves while shearing")
    lid_start_gap_m: Length = Field(0.030, description="the lid starts this far above the packing")
    max_normal_force_n: float | None = Field(
        None, gt=0, le=_MAX_FORCE_N,
        description="the loading system's range (the largest lid force it applies); unset: not stated")
    dst_normal_stresses_pa: list[Annotated[float, Field(gt=0, le=_MAX_STRESS_PA)]] | None = Field(
        None, min_length=2, max_length=_MAX_LOADS, description="DST normal stresses (give these or the forces)")
    dst_normal_forces_n: list[Annotated[float, Field(gt=0, le=_MAX_FORCE_N)]] | None = Field(
        None, min_length=2, max_length=_MAX_LOADS,
        description="DST normal forces on the lid, turned into stresses over the container area")
    cct_max_stress_pa: float | None = Field(None, gt=0, le=_MAX_STRESS_PA,
                                            description="CCT peak normal stress (give this or the force)")
    cct_max_force_n: float | None = Field(None, gt=0, le=_MAX_FORCE_N, description="CCT peak lid force")
    cct_cycles: WholeNumber = Field(4, ge=1, le=_MAX_CYCLES, description="CCT load-unload cycles")
    lid_speed_m_s: Speed = Field(0.001, description="lid speed of the CCT and the DST's loading")
    shear_speed_m_s: Speed = Field(0.001, description="DST shear speed")
    shear_distance_m: Length = Field(..., description="DST shear travel")

    @field_validator("gap_m")
    @classmethod
    def _gap_within_halves(cls, gap: float, info: ValidationInfo) -> float:
        halves = [info.data.get(k) for k in ("bottom_half_height_m", "top_half_height_m")]
        if all(h is not None for h in halves) and gap >= min(halves):
            raise ValueError(f"a gap of {gap * 1000:g} mm is not smaller than a half ({min(halves) * 1000:g} mm)")
        return gap

    @field_validator("dst_normal_stresses_pa", "dst_normal_forces_n")
    @classmethod
    def _distinct_within_range(cls, loads: list[float] | None, info: ValidationInfo) -> list[float] | None:
        if loads is None:
            return None
        if len(set(loads)) != len(loads):
            raise ValueError("the DST loads must be distinct (each load's result is keyed by its stress)")
        _within_range(loads, info.field_name, info.data)
        return loads

    @field_validator("cct_max_stress_pa", "cct_max_force_n")
    @classmethod
    def _cct_within_range(cls, load: float | None, info: ValidationInfo) -> float | None:
        if load is not None:
            _within_range([load], info.field_name, info.data)
        return load

    @field_validator("shear_distance_m")
    @classmethod
    def _shear_within_box(cls, distance: float, info: ValidationInfo) -> float:
        diameter = info.data.get("container_diameter_m")
        if diameter is not None and distance >= diameter:
            raise ValueError(f"{distance * 1000:g} mm of travel would part the halves of a "
                             f"{diameter * 1000:g} mm box: the travel must be smaller than the diameter")
        return distance

    @model_validator(mode="after")
    def _one_of_stress_or_force(self):
        for stresses, forces in (("dst_normal_stresses_pa", "dst_normal_forces_n"),
                                 ("cct_max_stress_pa", "cct_max_force_n")):
            if (getattr(self, stresses) is None) == (getattr(self, forces) is None):
                raise ValueError(f"give exactly one of {stresses} and {forces}")
        return self

    @property
    def container_radius_m(self) -> float:
        return 0.5 * self.container_diameter_m

    @property
    def container_area_m2(self) -> float:
        return math.pi * self.container_radius_m ** 2

    @property
    def container_height_m(self) -> float:
        return self.bottom_half_height_m + self.top_half_height_m

    @property
    def dst_stresses_pa(self) -> tuple[float, ...]:
        if self.dst_normal_stresses_pa is not None:
            return tuple(self.dst_normal_stresses_pa)
        return tuple(f / self.container_area_m2 for f in self.dst_normal_forces_n)

    @property
    def cct_stress_pa(self) -> float:
        if self.cct_max_stress_pa is not None:
            return self.cct_max_stress_pa
        return self.cct_max_force_n / self.container_area_m2


def _within_range(loads: list[float], field: str, data: dict) -> None:
    """Refuse a load beyond the loading system's range (``max_normal_force_n``), as a force on the lid."""
    limit, diameter = data.get("max_normal_force_n"), data.get("container_diameter_m")
    if limit is None or diameter is None:
        return
    area = math.pi * (0.5 * diameter) ** 2
    for index, load in enumerate(loads):
        force = load if field.endswith("_n") else load * area
        if force > limit * (1 + 1e-12):
            where = f" (load {index + 1})" if len(loads) > 1 else ""
            raise ValueError(f"{load:g}{' N' if field.endswith('_n') else ' Pa'}{where} is a lid force of "
                             f"{force:.6g} N, beyond the rig's range max_normal_force_n = {limit:g} N")


class Fill(BaseModel):
    """How the shear-box container is filled: poured, settled, struck off level (thesis section 4.5.4)."""

    model_config = _MODEL
    level_height_m: Length = Field(..., description="height the packing is struck off at (the brim: the container height)")
    drop_height_m: float = Field(0.0, ge=0, le=_MAX_LENGTH_M,
                                 description="free fall of the poured particles above the top of the simulated "
                                             "rainfall column (thesis: particles poured from up to 4.7 m)")
    height_rule: Literal["struck_off", "highest_sphere_top"] = Field(
        "struck_off",
        description="how the packing's height, and so its bulk volume, is read after levelling: 'struck_off' "
                    "as a laboratory does (a straightedge across the level, the bulk volume the container's to "
                    "it, the packing height the level itself), 'highest_sphere_top' as the thesis's DEM did "
                    "(section 4.5.4: the highest sphere's centre plus its radius, about a grain radius above "
                    "the level)")


class AngleOfRepose(BaseModel):
    """Bottomless bucket (a frustum) filled on a floor and lifted (thesis section 5.2)."""

    model_config = _MODEL
    bucket_bottom_diameter_m: Length
    bucket_top_diameter_m: Length
    bucket_height_m: Length
    fill_height_m: Length
    lift_speed_m_s: Speed
    wide_end_down: bool = Field(False, description="the bucket stands on its wide rim (False: narrow end down, "
                                                   "as the thesis's)")
    bucket_friction: Friction = Field(..., description="particle-bucket friction coefficient")
    floor_friction: Friction = Field(..., description="particle-floor friction coefficient")

    @field_validator("fill_height_m")
    @classmethod
    def _fill_within_bucket(cls, fill: float, info: ValidationInfo) -> float:
        height = info.data.get("bucket_height_m")
        if height is not None and fill > height:
            raise ValueError(f"{fill:g} m is above the bucket's rim ({height:g} m)")
        return fill


class Anchor(BaseModel):
    """Anchor pull-out: a square bin and an anchor (square tube on a foot plate) pulled up (section 5.3)."""

    model_config = _MODEL
    tube_width_m: Length
    tube_length_m: Length
    plate_width_m: Length
    plate_thickness_m: Length
    bin_width_m: Length
    packing_height_m: Length
    pull_speed_m_s: Speed
    acceleration_time_s: float = Field(1.0, ge=0, le=1e4)
    pull_distance_m: Length
    anchor_friction: Friction
    bin_friction: Friction

    @field_validator("plate_width_m")
    @classmethod
    def _plate_holds_tube(cls, plate: float, info: ValidationInfo) -> float:
        tube = info.data.get("tube_width_m")
        if tube is not None and plate < tube:
            raise ValueError(f"the foot plate ({plate:g} m) is narrower than the tube ({tube:g} m)")
        return plate

    @field_validator("bin_width_m")
    @classmethod
    def _bin_holds_plate(cls, width: float, info: ValidationInfo) -> float:
        plate = info.data.get("plate_width_m")
        if plate is not None and width <= plate:
            raise ValueError(f"the bin ({width:g} m) is not wider than the anchor's plate ({plate:g} m)")
        return width

    @field_validator("packing_height_m")
    @classmethod
    def _anchor_reaches_out(cls, height: float, info: ValidationInfo) -> float:
        length, plate = info.data.get("tube_length_m"), info.data.get("plate_thickness_m")
        if length is not None and plate is not None and height >= length + plate:
            raise ValueError(f"a {height:g} m packing buries the whole anchor ({length + plate:g} m)")
        return height


class Rig(BaseModel):
    """One laboratory's apparatus; a section per test kind it can run (unset: that test is not in this rig)."""

    model_config = _MODEL
    name: str = Field(..., min_length=1, max_length=200, pattern=r"^[A-Za-z0-9][A-Za-z0-9 ._()-]*$")
    description: str = Field("", max_length=10_000)
    source: str = Field("", max_length=10_000)
    shear_box: ShearBox | None = None
    fill: Fill | None = None
    angle_of_repose: AngleOfRepose | None = None
    anchor: Anchor | None = None

    @field_validator("fill")
    @classmethod
    def _level_within_container(cls, fill: Fill | None, info: ValidationInfo) -> Fill | None:
        box = info.data.get("shear_box")
        if fill is not None and box is not None and fill.level_height_m > box.container_height_m * (1 + 1e-12):
            raise ValueError(f"level_height_m {fill.level_height_m:g} m is above the container's brim "
                             f"({box.container_height_m:g} m)")
        return fill


def check_for_particles(rig: Rig, particles: Particles) -> list[str]:
    """Refuse what cannot run with these particles (``SpecFieldError`` naming the rig's field); return the
    warnings of what runs but is outside the direct-shear standards' sizes."""
    warnings: list[str] = []
    box = rig.shear_box
    if box is None:
        return warnings
    smallest, largest = particles.smallest_particle_size_m, particles.largest_particle_size_m
    if box.gap_m >= smallest:
        raise SpecFieldError("shear_box.gap_m",
                             f"a gap of {box.gap_m * 1000:g} mm lets the smallest particles "
                             f"({smallest * 1000:.3g} mm) fall through; make it smaller than a particle")
    if box.container_diameter_m < MIN_DIAMETER_PER_PARTICLE * largest:
        warnings.append(
            f"shear_box.container_diameter_m: {box.container_diameter_m * 1000:g} mm is "
            f"{box.container_diameter_m / largest:.1f} largest particles ({largest * 1000:.3g} mm) across; the "
            f"direct-shear standards ask for at least {MIN_DIAMETER_PER_PARTICLE:g}: the box may constrain the "
            "shear band and overstate strength")
    # the specimen is what the box holds: the packing struck off at the fill level (else the full container)
    field, thickness = (("fill.level_height_m", rig.fill.level_height_m) if rig.fill is not None
                        else ("shear_box.top_half_height_m", box.container_height_m))
    if thickness < MIN_THICKNESS_PER_PARTICLE * largest:
        warnings.append(
            f"{field}: the specimen is {thickness * 1000:g} mm thick, {thickness / largest:.1f} largest particles "
            f"({largest * 1000:.3g} mm); the direct-shear standards ask for at least "
            f"{MIN_THICKNESS_PER_PARTICLE:g}")
    return warnings


def load_record(path: Path) -> Rig:
    return Rig.model_validate_json(path.read_text())


@lru_cache(maxsize=None)
def bundled_rigs() -> dict[str, Rig]:
    """The read-only rigs shipped with demcal, by name (the thesis's and Appendix A's)."""
    rigs = {}
    for path in sorted(RECORDS_DIR.glob("*.json")):
        rig = load_record(path)
        rigs[rig.name] = rig
    return rigs


def bundled_rig(name: str) -> Rig:
    try:
        return bundled_rigs()[name]
    except KeyError:
        raise SpecFieldError("rig", f"unknown bundled rig {name!r}; choose one of {sorted(bundled_rigs())}") from None


def rig_json(rig: Rig) -> dict:
    """The record as stored and served (unset sections and fields left out)."""
    return json.loads(rig.model_dump_json(exclude_none=True))
