"""Materials service layer: create, read, seed. API and CLI both go through here."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from sqlalchemy import func, select
from sqlalchemy.orm import Session, selectinload

from calibration.keys import ResponseKey
from engine.lab.plausibility import record_warnings
from service.api.jsonsafe import json_safe
from service.errors import Conflict, Invalid
from service.materials.schemas import FieldError, MaterialIn, MeasurementIn
from service.models.material import Material, Measurement
from service.models.rig import Rig
from service.rigs.store import find_by_name as find_rig
from service.rigs.store import particles_warnings, record_of, seed_bundled_rigs
from service.pagination import paged

BUNDLED_DIR = Path(__file__).parent
BUNDLED_FILES = ("thesis_coarse_aggregate.json",)


def material_dict(material: Material) -> dict[str, Any]:
    """The API view; rows written before validation existed may hold NaN/inf, shown as null
    (``json_safe``) so one bad row never breaks a listing."""
    return json_safe({
        "id": material.id, "name": material.name, "description": material.description,
        "source": material.source, "bundled": material.bundled, "owner": material.owner,
        "direct_estimates": dict(material.direct_estimates or {}),
        "rig_id": material.rig_id, "rig": material.rig.name if material.rig is not None else None,
        "particles": material.particles, "warnings": rig_warnings(material),
        "measurements": [measurement_dict(m) for m in material.measurements],
        "created_at": material.created_at.isoformat() + "Z",
    })


def measurement_dict(row: Measurement) -> dict[str, Any]:
    """The API view of a stored measurement with its plausibility warnings, the same words at entry, in
    every listing and in the reports that use it."""
    try:
        return json_safe({**row.as_dict(), "warnings": record_warnings([row])})
    except (TypeError, ValueError, ZeroDivisionError, OverflowError):  # an unreadable legacy row
        return json_safe({**{k: getattr(row, k, None) for k in ("id", "material_id", "test", "quantity", "unit",
                                                                   "input_unit", "source")},
                          "condition": {}, "values": [], "n": 0, "reported_replicates": None, "mean": None,
                          "standard_uncertainty": None, "created_at": None, "warnings": []})


def rig_warnings(material: Material) -> list[str]:
    """The rig too small for the material's particles (engine.lab.rigs.check_for_particles); none when either
    is unset. A record stored before a check existed that now fails it shows its refusal as a warning."""
    if material.rig is None or material.particles is None:
        return []
    try:
        return particles_warnings(record_of(material.rig), material.particles, "rig.")
    except Invalid as exc:
        return [f"{'.'.join(str(p) for p in exc.loc()[1:])}: {exc.message}"]


def resolve_rig(session: Session, data: MaterialIn) -> Rig | None:
    """The rig row the material names (422 naming ``rig`` if none has that name), checked against the
    material's particles: a gap they fall through is refused naming the rig's field."""
    if data.rig is None:
        return None
    row = find_rig(session, data.rig)
    if row is None:
        raise FieldError("rig", f"no rig named {data.rig!r} (GET /api/v1/rigs lists them)")
    if data.particles is not None:
        particles_warnings(record_of(row), data.particles.model_dump(mode="json"), "rig.")
    return row


def require_editable(material: Material) -> None:
    """The bundled reference material is read-only: it is the test data of the founding case, and a
    calibration against it must mean the same thing on every installation. Copy it to edit."""
    if material.bundled:
        raise Conflict(f"material {material.id} ({material.name!r}) is bundled reference data and read-only; "
                       f"copy it (POST /api/v1/materials/{material.id}/copy) to edit", ["path", "material_id"])


def copy_material(session: Session, material: Material, name: str, owner: str | None = None) -> Material:
    """An editable copy (not bundled) with the same measurements, under a new name, owned by ``owner``
    (copying reads the original, whoever owns it)."""
    copy = Material(name=name, description=material.description, source=material.source, bundled=False,
                    direct_estimates=dict(material.direct_estimates or {}), rig_id=material.rig_id,
                    particles=material.particles, owner=owner)
    session.add(copy)
    for row in material.measurements:
        copy.measurements.append(Measurement(
            test=row.test, quantity=row.quantity, condition=dict(row.condition), unit=row.unit,
            values=list(row.values), reported_replicates=row.reported_replicates,
            stated_uncertainty=row.stated_uncertainty, input_unit=row.input_unit, source=row.source))
    return copy


def get_material(session: Session, material_id: int) -> Material | None:
    return session.get(Material, material_id, options=[selectinload(Material.measurements)])


def list_materials(session: Session, limit: int, offset: int) -> tuple[list[Material], int]:
    """A page of materials by id, with their measurements, and the total."""
    return paged(session, Material, order=(Material.id,), options=(selectinload(Material.measurements),),
                 limit=limit, offset=offset)


def find_by_name(session: Session, name: str) -> Material | None:
    return session.scalar(select(Material).where(Material.name == name))


def same_key(rows, record) -> Measurement | None:
    """The row among ``rows`` whose measurement key (calibration.keys.ResponseKey: test, quantity, and the
    condition within its tolerance) is ``record``'s. The calibration matches a measurement to a simulated
    value by that key, so it also decides what counts as the same measurement in storage: 24 kPa
    entered in kPa and 24,000 Pa entered in Pa are one condition."""
    key = ResponseKey.from_record(record)
    return next((row for row in rows if ResponseKey.from_record(row).matches(key)), None)


def add_measurement(session: Session, material: Material, data: MeasurementIn) -> Measurement:
    """Converts to SI (raises schemas.FieldError on bad units or bounds) and attaches to the material.

    A second measurement of the same key (``same_key``) is refused, naming the one stored: the
    calibration matches one measurement per key, and silently keeping one of two is losing data. Add
    replicates to the values of the existing one instead (delete and re-add it with all of them)."""
    fields = data.to_si()
    existing = same_key(material.measurements, fields)
    if existing is not None:
        where = f"measurement {existing.id}" if existing.id is not None else "an earlier measurement"
        raise FieldError("condition", f"{where} already holds {ResponseKey.from_record(existing).label} (SI), the "
                         f"same measurement as {ResponseKey.from_record(fields).label}: put all replicates in one "
                         "measurement's values")
    row = Measurement(**fields)
    material.measurements.append(row)
    return row


def create_material(session: Session, data: MaterialIn, *, bundled: bool = False, owner: str | None = None) -> Material:
    rig = resolve_rig(session, data)
    material = Material(name=data.name, description=data.description, source=data.source,
                        bundled=bundled, direct_estimates=data.direct_estimates, rig=rig, owner=owner,
                        particles=None if data.particles is None else data.particles.model_dump(mode="json",
                                                                                               exclude_none=True))
    session.add(material)
    for index, meas in enumerate(data.measurements):
        try:
            add_measurement(session, material, meas)
        except Exception as exc:  # name the measurement in the error location
            if hasattr(exc, "field"):
                exc.field = f"measurements.{index}.{exc.field}"
            raise
    return material


def latest_measurement_id(session: Session, material_id: int) -> int | None:
    return session.scalar(select(func.max(Measurement.id)).where(Measurement.material_id == material_id))


def load_bundled(filename: str) -> MaterialIn:
    return MaterialIn.model_validate(json.loads((BUNDLED_DIR / filename).read_text()))


def seed_bundled_materials(session: Session) -> list[int]:
    """Insert the bundled materials that are missing (by name), and any of their measurements that are
    missing (deleted before the material became read-only); idempotent, commits.

    Called at service start: the reference data is there, complete, after every start.
    """
    seed_bundled_rigs(session)  # the bundled material names the thesis rig
    ids = []
    for filename in BUNDLED_FILES:
        data = load_bundled(filename)
        existing = find_by_name(session, data.name)
        if existing is None:
            existing = create_material(session, data, bundled=True)
        else:
            existing.bundled = True
            # a database from before rigs and particles existed: the bundled material gains them
            if existing.rig is None:
                existing.rig = resolve_rig(session, data)
            if existing.particles is None and data.particles is not None:
                existing.particles = data.particles.model_dump(mode="json", exclude_none=True)
            for meas in data.measurements:
                fields = meas.to_si()
                if same_key(existing.measurements, fields) is None:
                    existing.measurements.append(Measurement(**fields))
        session.flush()
        ids.append(existing.id)
    session.commit()
    return ids
