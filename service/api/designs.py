"""Design preview: what a campaign would run, before anything is queued."""
from __future__ import annotations

from fastapi import APIRouter, Request

from calibration.design import build_design, design_view
from service.campaigns.schemas import DesignPreviewIn
from service.api.responses.designs import DesignView
from service.limits import check_design_size

router = APIRouter(prefix="/designs", tags=["designs"])


@router.post("/preview", summary="Design table (natural and coded), alias structure and resolution",
             response_model=DesignView)
def preview(body: DesignPreviewIn, request: Request) -> dict:
    # sized before it is built: the runs (and the answer) grow as 2^k x replicates
    check_design_size(len(body.factors), len(body.generators or ()), body.replicates, body.centre_runs,
                      request.app.state.settings)
    view = design_view(build_design(body.factors, body, body.seed, field_prefix=""))
    view.pop("doe")
    return view
