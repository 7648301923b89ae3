"""Exports of a calibrated material: the material card (JSON or YAML), every registered export format,
the card's import as a material with fixed parameters, and the shareable HTML report of a campaign."""
from __future__ import annotations

from typing import Literal

from fastapi import APIRouter, Query, Request, Response
from fastapi.responses import HTMLResponse, PlainTextResponse
from pydantic import BaseModel

from service.api.openapi import errors
from service.api.params import CampaignId, MaterialId
from service.db import DbSession, built_then_committed
from service.errors import Invalid
from service.export import card as cards
from service.export import formats
from service.export.store import campaign_card, calibrated_iteration, demcal_version, import_card, material_card
from service.materials.schemas import MaterialOut

router = APIRouter(tags=["export"])

_NOT_CALIBRATED = errors(409, c409="the campaign has no calibrated iteration (report) yet")
# the card's schema documents the JSON answer; YAML is the same card as text
_CARD = {200: {"content": {"application/yaml": {"schema": {"type": "string"}}},
               "description": "the card (JSON; YAML with ?format=yaml or Accept: application/yaml)"}}


class ExportFormatOut(BaseModel):
    name: str
    media_type: str
    suffix: str
    description: str


IterationQ = Query(None, ge=1, le=2**63 - 1,
                   description="iteration number; default the model the loop keeps (the latest report's, or the "
                               "iteration an effect it rejected was built on)")
CardFormat = Query(None, description="json (default) or yaml; an Accept of application/yaml also gives YAML")


def _card_response(request: Request, card: dict, fmt: str | None, filename: str) -> Response:
    wants_yaml = fmt == "yaml" or (fmt is None and "yaml" in request.headers.get("accept", ""))
    chosen = formats.get("card" if wants_yaml else "card-json")
    return Response(chosen.render(card), media_type=chosen.media_type,
                    headers={"Content-Disposition": f'inline; filename="{filename}{chosen.suffix}"'})


@router.get("/campaigns/{campaign_id}/material-card", responses={**_NOT_CALIBRATED, **_CARD},
            response_model=cards.MaterialCard,
            summary="The calibrated material as a neutral card: particles, contact law and effects in SI with units, "
                    "the calibrated values with their uncertainty, the rig, the measurements' provenance (docs/export.md)")
def campaign_material_card(campaign_id: CampaignId, request: Request, session: DbSession,
                           format: Literal["json", "yaml"] | None = CardFormat, number: int | None = IterationQ):
    return _card_response(request, campaign_card(session, campaign_id, number), format, f"campaign-{campaign_id}")


@router.get("/campaigns/{campaign_id}/export", response_model=str,
            responses={**_NOT_CALIBRATED, 200: {"description": "the file, in its format's media type", "content": {
                media: {"schema": {"type": "string"}} for media in sorted({f.media_type for f in formats.FORMATS.values()})}}},
            response_class=PlainTextResponse,
            summary="The calibrated material in a registered export format (service.export.formats), as a file")
def export(campaign_id: CampaignId, session: DbSession,
           format: str = Query("card", max_length=32, description="an export format: GET /export-formats"),
           number: int | None = IterationQ):
    try:
        chosen = formats.get(format)
    except ValueError as exc:
        raise Invalid(str(exc), ["query", "format"]) from None
    text = chosen.render(campaign_card(session, campaign_id, number))
    return Response(text, media_type=chosen.media_type,
                    headers={"Content-Disposition": f'attachment; filename="campaign-{campaign_id}{chosen.suffix}"'})


@router.get("/export-formats", summary="The export formats of a calibrated material",
            response_model=list[ExportFormatOut])
def export_formats() -> list[dict[str, str]]:
    return [{"name": f.name, "media_type": f.media_type, "suffix": f.suffix, "description": f.description}
            for f in (formats.FORMATS[n] for n in formats.names())]


@router.get("/materials/{material_id}/material-card", response_model=cards.MaterialCard,
            responses={**errors(404, 409, c409="the material was not imported from a material card"), **_CARD},
            summary="The card of a material imported from one (the round trip of the import)")
def imported_material_card(material_id: MaterialId, request: Request, session: DbSession,
                           format: Literal["json", "yaml"] | None = CardFormat):
    return _card_response(request, material_card(session, material_id), format, f"material-{material_id}")


@router.post("/materials/import-card", status_code=201, response_model=MaterialOut,
             responses=errors(409, c409="a material with this name exists"),
             summary="Create a material with fixed parameters from a material card (JSON body; the CLI reads YAML too)")
def import_material_card(card: cards.MaterialCard, session: DbSession,
                         name: str | None = Query(None, min_length=1, max_length=200,
                                                  description="the new material's name; default the card's")):
    from service.materials.store import get_material, material_dict

    material = import_card(session, card.model_dump(mode="json"), name)
    session.flush()
    return built_then_committed(session, lambda: material_dict(get_material(session, material.id)), MaterialOut)


@router.get("/campaigns/{campaign_id}/report.html", response_class=HTMLResponse, response_model=str,
            responses=_NOT_CALIBRATED,
            summary="The campaign's verdict, targets, diagnosis and history as one self-contained HTML file "
                    "(inline CSS and SVG charts, no scripts, nothing loaded from elsewhere)")
def report_html(campaign_id: CampaignId, session: DbSession, number: int | None = IterationQ,
                download: bool = Query(False, description="as an attachment (Content-Disposition) to save")):
    from calibration.history import history
    from service.campaigns.store import campaign_summary, get_campaign
    from service.export.report_html import render
    from service.materials.store import get_material

    campaign = get_campaign(session, campaign_id)
    it = calibrated_iteration(campaign, number)
    material = get_material(session, campaign.material_id)
    html = render(summary=campaign_summary(campaign), report=it.report, iteration=it.number,
                  history=history(campaign.iterations), material_name=material.name if material else "?",
                  parameter_std=(it.optimum or {}).get("parameter_std"),
                  factors=(it.parameters or {}).get("factors", (campaign.config or {}).get("factors", [])),
                  demcal_version=demcal_version())
    disposition = "attachment" if download else "inline"
    return HTMLResponse(html, headers={"Content-Disposition": f'{disposition}; filename="campaign-{campaign_id}-report.html"'})

