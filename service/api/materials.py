"""Materials and measurements endpoints. Values go in with any accepted unit, come out SI."""
from __future__ import annotations

from fastapi import APIRouter, Depends, Response
from sqlalchemy import select
from sqlalchemy.orm import Session

from service.api.openapi import errors
from service.api.params import MaterialId, MaterialLimit, MeasurementId, MeasurementLimit, Offset
from service.api.responses.quantities import Quantities
from service.db import DbSession, built_then_committed
from service.errors import Conflict, NotFound
from service.materials.schemas import (MaterialCopy, MaterialIn, MaterialList, MaterialOut, MeasurementIn, MeasurementList,
                                       MeasurementOut)
from service.materials.store import (add_measurement, copy_material, create_material, find_by_name, get_material,
                                     list_materials, material_dict, measurement_dict, require_editable)
from engine.lab.registry import tests
from service.api.tests import quantity_out
from service.models.campaign import Campaign
from service.models.material import Measurement
from service.ownership import Caller, caller, owner_of
from service.pagination import paged

router = APIRouter(prefix="/materials", tags=["materials"])


def _material_or_404(session: Session, material_id: int):
    """The material, or a 404 naming the path parameter."""
    material = get_material(session, material_id)
    if material is None:
        raise NotFound(f"material {material_id} not found", ["path", "material_id"])
    return material


@router.get("/quantities",
            summary="Canonical tests, quantities, SI units, accepted input units and physical bounds (SI)",
            response_model=Quantities)
def quantities() -> dict:
    """The lab-test registry's quantities by test and name (GET /tests has the whole catalogue)."""
    return {name: {q.name: quantity_out(q).model_dump(include={"si_unit", "accepted_units", "bounds"})
                   for q in test.quantities}
            for name, test in tests().items()}


@router.get("", response_model=MaterialList, summary="List materials with their measurements, by id; a page and the total")
def list_all(session: DbSession, limit: MaterialLimit = 50, offset: Offset = 0):
    rows, total = list_materials(session, limit, offset)
    return {"items": [material_dict(m) for m in rows], "total": total, "limit": limit, "offset": offset}


def _editable(material, who: Caller) -> None:
    """Bundled reference data is read-only for everyone (409); another user's material is theirs (403)."""
    require_editable(material)
    who.require(material.owner, f"material {material.id}", ["path", "material_id"])


@router.post("", response_model=MaterialOut, status_code=201,
             summary="Create a material (optionally with measurements)",
             responses=errors(409, c409="a material with this name exists"))
def create(body: MaterialIn, session: DbSession, owner: str | None = Depends(owner_of)):
    if find_by_name(session, body.name) is not None:
        raise Conflict(f"a material named {body.name!r} exists", "name")
    material = create_material(session, body, owner=owner)
    return built_then_committed(session, lambda: material_dict(_material_or_404(session, material.id)), MaterialOut)


@router.post("/{material_id}/copy", response_model=MaterialOut, status_code=201,
             summary="Copy a material (e.g. the read-only bundled one) under a new name, to edit it",
             responses=errors(409, c409="a material with this name exists"))
def copy(material_id: MaterialId, body: MaterialCopy, session: DbSession, owner: str | None = Depends(owner_of)):
    material = _material_or_404(session, material_id)
    if find_by_name(session, body.name) is not None:
        raise Conflict(f"a material named {body.name!r} exists", "name")
    created = copy_material(session, material, body.name, owner=owner)  # the copy is the copier's
    return built_then_committed(session, lambda: material_dict(_material_or_404(session, created.id)), MaterialOut)


@router.get("/{material_id}", response_model=MaterialOut)
def show(material_id: MaterialId, session: DbSession):
    return material_dict(_material_or_404(session, material_id))


@router.delete("/{material_id}", status_code=204, summary="Delete a material no campaign uses (not the bundled one)",
               responses=errors(403, 409, c403="another user's material",
                                c409="the material is bundled (read-only) or used by a campaign"))
def delete(material_id: MaterialId, session: DbSession, who: Caller = Depends(caller)):
    material = _material_or_404(session, material_id)
    _editable(material, who)
    if session.scalar(select(Campaign.id).where(Campaign.material_id == material_id).limit(1)) is not None:
        raise Conflict(f"material {material_id} is used by campaigns; it cannot be deleted", ["path", "material_id"])
    session.delete(material)
    session.commit()
    return Response(status_code=204)


@router.get("/{material_id}/measurements", response_model=MeasurementList,
            summary="A material's measurements, by id; a page and the total")
def list_measurements(material_id: MaterialId, session: DbSession, limit: MeasurementLimit = 100, offset: Offset = 0):
    _material_or_404(session, material_id)
    rows, total = paged(session, Measurement, where=[Measurement.material_id == material_id], order=(Measurement.id,),
                        limit=limit, offset=offset)
    return {"items": [measurement_dict(m) for m in rows], "total": total, "limit": limit, "offset": offset}


@router.post("/{material_id}/measurements", response_model=MeasurementOut, status_code=201,
             summary="Add a measurement (replicates in any accepted unit; stored SI)",
             responses=errors(403, 409, c403="another user's material",
                              c409="the material is bundled reference data (read-only)"))
def add(material_id: MaterialId, body: MeasurementIn, session: DbSession, who: Caller = Depends(caller)):
    material = _material_or_404(session, material_id)
    _editable(material, who)
    row = add_measurement(session, material, body)
    return built_then_committed(session, lambda: measurement_dict(row), MeasurementOut)


@router.delete("/{material_id}/measurements/{measurement_id}", status_code=204,
               responses=errors(403, 409, c403="another user's material",
                                c409="the material is bundled reference data (read-only)"))
def delete_measurement(material_id: MaterialId, measurement_id: MeasurementId, session: DbSession,
                       who: Caller = Depends(caller)):
    _editable(_material_or_404(session, material_id), who)
    row = session.get(Measurement, measurement_id)
    if row is None or row.material_id != material_id:
        raise NotFound(f"measurement {measurement_id} not found in material {material_id}",
                       ["path", "measurement_id"])
    session.delete(row)
    session.commit()
    return Response(status_code=204)
