"""Rigs endpoints: the apparatus records measurements are made in (engine.lab.rigs.Rig, SI)."""
from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Depends, Path, Query
from pydantic import BaseModel, ConfigDict, Field
from sqlalchemy.orm import Session

from engine.lab.bounds import ID_MAX
from engine.lab.rigs import Rig
from service.api.openapi import errors
from service.api.params import Offset, page_limit
from service.api.responses.common import Page
from service.db import DbSession, built_then_committed
from service.errors import NotFound
from service.ownership import Caller, caller, owner_of
from service.materials.store import get_material
from service.rigs.store import (create_rig, list_rigs, particles_warnings, record_of, replace_rig, require_editable,
                                rig_dict)
from service.models.rig import Rig as RigRow

router = APIRouter(prefix="/rigs", tags=["rigs"])

RigId = Annotated[int, Path(ge=1, le=ID_MAX, description="rig id")]
ForMaterial = Annotated[int | None, Query(ge=1, le=ID_MAX,
                                          description="check the rig against this material's particles: a gap they "
                                                      "fall through is refused, a box too small for them warned")]


RigLimit = page_limit(500)


class RigOut(Rig):
    """A stored rig: the record, its id, whether it is bundled (read-only), and the warnings of a check."""

    model_config = ConfigDict(extra="forbid", strict=False)
    id: int
    bundled: bool
    owner: str | None = Field(None, description="the user who made it (none: bundled, or made without a token)")
    created_at: str
    updated_at: str
    warnings: list[str] = Field(default_factory=list, description="sizes outside the direct-shear standards' "
                                "(against ?material_id's particles); the rig is stored all the same")


class RigCheck(BaseModel):
    rig_id: int
    material_id: int
    warnings: list[str]


def _rig_or_404(session: Session, rig_id: int) -> RigRow:
    row = session.get(RigRow, rig_id)
    if row is None:
        raise NotFound(f"rig {rig_id} not found", ["path", "rig_id"])
    return row


def _warnings(session: Session, rig: Rig, material_id: int | None) -> list[str]:
    if material_id is None:
        return []
    material = get_material(session, material_id)
    if material is None:
        raise NotFound(f"material {material_id} not found", ["query", "material_id"])
    return particles_warnings(rig, material.particles)


class RigList(Page):
    """A page of rigs, by id."""

    items: list[RigOut]


@router.get("", response_model=RigList,
            summary="List rigs by id (the bundled ones are seeded at first start); a page and the total")
def list_all(session: DbSession, limit: RigLimit = 100, offset: Offset = 0) -> dict[str, Any]:
    rows, total = list_rigs(session, limit, offset)
    return {"items": [rig_dict(row) for row in rows], "total": total, "limit": limit, "offset": offset}


@router.post("", response_model=RigOut, status_code=201, summary="Create a rig",
             responses=errors(404, 409, c404="the material named by ?material_id does not exist",
                              c409="a rig with this name exists"))
def create(body: Rig, session: DbSession, material_id: ForMaterial = None,
           owner: str | None = Depends(owner_of)):
    warnings = _warnings(session, body, material_id)
    row = create_rig(session, body, owner=owner)
    return built_then_committed(session, lambda: rig_dict(row, warnings), RigOut)


@router.get("/{rig_id}", response_model=RigOut)
def show(rig_id: RigId, session: DbSession, material_id: ForMaterial = None):
    row = _rig_or_404(session, rig_id)
    return rig_dict(row, _warnings(session, record_of(row), material_id))


@router.put("/{rig_id}", response_model=RigOut,
            summary="Replace a rig's record (not a bundled one, nor one a material names)",
            responses=errors(403, 409, c403="the rig is another user's",
                             c409="the rig is bundled (read-only) or a material's, or another rig has the name"))
def replace(rig_id: RigId, body: Rig, session: DbSession, material_id: ForMaterial = None,
            who: Caller = Depends(caller)):
    row = _rig_or_404(session, rig_id)
    require_editable(row)  # bundled: read-only for everyone (409), administrators included
    who.require(row.owner, f"rig {rig_id}", ["path", "rig_id"])
    warnings = _warnings(session, body, material_id)
    replace_rig(session, row, body)
    return built_then_committed(session, lambda: rig_dict(row, warnings), RigOut)


@router.get("/{rig_id}/check", response_model=RigCheck,
            summary="Check a rig against a material's particles (422 naming the field if they cannot run in it)")
def check(rig_id: RigId, session: DbSession, material_id: Annotated[int, Query(ge=1, le=ID_MAX)]):
    row = _rig_or_404(session, rig_id)
    return {"rig_id": rig_id, "material_id": material_id, "warnings": _warnings(session, record_of(row), material_id)}

