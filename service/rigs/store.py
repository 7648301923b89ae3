"""Rigs service layer: create, read, replace, seed, check against a material's particles. API and CLI go
through here; the record itself is validated by ``engine.lab.rigs.Rig`` (a 422 names the field)."""
from __future__ import annotations

from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from service.pagination import paged

from engine.lab.errors import SpecFieldError
from engine.lab.rigs import Rig, bundled_rigs, check_for_particles, rig_json
from engine.particles.description import Particles
from service.errors import Conflict, Invalid
from service.models.material import Material
from service.models.rig import Rig as RigRow


def rig_dict(row: RigRow, warnings: list[str] | None = None) -> dict[str, Any]:
    """The API view: the record's fields, with the row's id, bundled flag and times."""
    out = {**row.record, "id": row.id, "bundled": row.bundled, "owner": row.owner,
           "created_at": row.created_at.isoformat() + "Z", "updated_at": row.updated_at.isoformat() + "Z"}
    if warnings is not None:
        out["warnings"] = warnings
    return out


def record_of(row: RigRow) -> Rig:
    return Rig.model_validate(row.record)


def list_rigs(session: Session, limit: int, offset: int) -> tuple[list[RigRow], int]:
    """A page of rigs by id, and the total."""
    return paged(session, RigRow, order=(RigRow.id,), limit=limit, offset=offset)


def find_by_name(session: Session, name: str) -> RigRow | None:
    return session.scalar(select(RigRow).where(RigRow.name == name))


def require_editable(row: RigRow) -> None:
    """Bundled rigs are read-only: the thesis tables and every result that names them must keep meaning
    the same apparatus. Create a rig under a new name to change one."""
    if row.bundled:
        raise Conflict(f"rig {row.id} ({row.name!r}) is a bundled record and read-only; create a rig under "
                       "a new name (POST /api/v1/rigs) with the changed dimensions", ["path", "rig_id"])


def particles_warnings(rig: Rig, particles: dict | None, where: str = "") -> list[str]:
    """``check_for_particles`` with the refusal as a 422 naming the rig's field (``where`` prefixes it)."""
    if particles is None:
        return []
    try:
        return check_for_particles(rig, Particles.model_validate(particles))
    except SpecFieldError as exc:
        raise Invalid(exc.message, f"{where}{exc.field}") from None


def create_rig(session: Session, rig: Rig, *, bundled: bool = False, owner: str | None = None) -> RigRow:
    if find_by_name(session, rig.name) is not None:
        raise Conflict(f"a rig named {rig.name!r} exists", "name")
    row = RigRow(name=rig.name, bundled=bundled, record=rig_json(rig), owner=owner)
    session.add(row)
    return row


def replace_rig(session: Session, row: RigRow, rig: Rig) -> RigRow:
    """A user's rig no material names yet: once one does, its measurements were made in this apparatus, and
    changing the record would change what they mean."""
    require_editable(row)
    users = list(session.scalars(select(Material.name).where(Material.rig_id == row.id).limit(3)))
    if users:
        raise Conflict(f"rig {row.id} ({row.name!r}) is the rig of material(s) {', '.join(map(repr, users))}: their "
                       "measurements were made in it; create a rig under a new name instead", ["path", "rig_id"])
    other = find_by_name(session, rig.name)
    if other is not None and other.id != row.id:
        raise Conflict(f"a rig named {rig.name!r} exists", "name")
    row.name, row.record = rig.name, rig_json(rig)
    return row


def seed_bundled_rigs(session: Session) -> dict[str, int]:
    """Insert the bundled rigs that are missing (by name) and restore a bundled record to its file;
    idempotent, commits. Called at service start, before the bundled material that names one."""
    ids = {}
    for name, rig in bundled_rigs().items():
        row = find_by_name(session, name)
        if row is None:
            row = create_rig(session, rig, bundled=True)
        else:
            row.bundled, row.record = True, rig_json(rig)
        session.flush()
        ids[name] = row.id
    session.commit()
    return ids
