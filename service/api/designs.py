"""Design preview: what a campaign would run, before anything is queued."""
from __future__ import annotations

from fastapi import APIRouter

from service.campaigns.design import build_design, design_view
from service.campaigns.schemas import DesignPreviewIn

router = APIRouter(prefix="/designs", tags=["designs"])


@router.post("/preview", summary="Design table (natural and coded), alias structure and resolution")
def preview(body: DesignPreviewIn) -> dict:
    view = design_view(build_design(body.factors, body, body.seed, field_prefix=""))
    view.pop("doe")
    return view
