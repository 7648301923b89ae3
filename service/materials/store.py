"""Materials service layer: create, read, seed. API and CLI both go through here."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from sqlalchemy import func, select
from sqlalchemy.orm import Session, selectinload

from service.materials.schemas import MaterialIn, MeasurementIn
from service.models.material import Material, Measurement

BUNDLED_DIR = Path(__file__).parent
BUNDLED_FILES = ("thesis_coarse_aggregate.json",)


def material_dict(material: Material) -> dict[str, Any]:
    return {
        "id": material.id, "name": material.name, "description": material.description,
        "source": material.source, "bundled": material.bundled,
        "direct_estimates": dict(material.direct_estimates or {}),
        "measurements": [m.as_dict() for m in material.measurements],
        "created_at": material.created_at.isoformat() + "Z",
    }


def get_material(session: Session, material_id: int) -> Material | None:
    return session.get(Material, material_id, options=[selectinload(Material.measurements)])


def list_materials(session: Session) -> list[Material]:
    return list(session.scalars(select(Material).options(selectinload(Material.measurements)).order_by(Material.id)))


def find_by_name(session: Session, name: str) -> Material | None:
    return session.scalar(select(Material).where(Material.name == name))


def add_measurement(session: Session, material: Material, data: MeasurementIn) -> Measurement:
    """Converts to SI (raises schemas.FieldError on bad units) and attaches to the material."""
    row = Measurement(**data.to_si())
    material.measurements.append(row)
    return row


def create_material(session: Session, data: MaterialIn, *, bundled: bool = False) -> Material:
    material = Material(name=data.name, description=data.description, source=data.source,
                        bundled=bundled, direct_estimates=data.direct_estimates)
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
    """Insert the bundled materials that are missing (by name); idempotent, commits.

    Called at service start (and safe to call on every start): a material already
    present is left as it is, so user edits to it survive restarts.
    """
    ids = []
    for filename in BUNDLED_FILES:
        data = load_bundled(filename)
        existing = find_by_name(session, data.name)
        if existing is None:
            existing = create_material(session, data, bundled=True)
            session.flush()
        ids.append(existing.id)
    session.commit()
    return ids
