"""Campaign endpoints: create, start/pause/resume (409 when illegal), and every product of a run."""
from __future__ import annotations

from fastapi import APIRouter, Depends, Query
from sqlalchemy.orm import Session

from service.campaigns.schemas import CampaignCreate, ContinueIn, IterationIn
from service.campaigns.store import (campaign_estimate, campaign_summary, continue_campaign, create_campaign,
                                     get_campaign, iteration, iteration_view, list_campaigns, next_iteration,
                                     retry_campaign, transition)
from service.api.openapi import errors
from service.api.params import CampaignId, CampaignLimit, IterationLimit, IterationNumber, Offset
from engine.lab.bounds import ID_MAX
from service.api.responses.campaigns import (CampaignDesign, CampaignList, CampaignModels, CampaignOptimum, CampaignSummary,
                                             Confirmation, Iteration, IterationList)
from service.api.responses.common import typed
from service.api.responses.diagnosis import DiagnosisOut
from service.api.responses.history import History
from service.api.responses.report import ReportOut
from service.db import DbSession, built_then_committed
from service.errors import Conflict, NotFound
from service.models.campaign import CampaignIteration
from service.pagination import paged
from service.ownership import Caller, caller, owner_of
from service.security import client_id
from calibration.vocabulary import Phase, Verdict
from service.vocabulary import CampaignStatus

router = APIRouter(prefix="/campaigns", tags=["campaigns"])

_STATE = errors(403, 409, c403="another user's campaign", c409="the campaign's status does not allow this")
_NOT_YET = errors(409, c409="the iteration has not produced this yet")


@router.post("", status_code=201, summary="Create a campaign (draft) for a material", **typed(CampaignSummary),
             responses=errors(404, c404="the material does not exist"))
def create(body: CampaignCreate, session: DbSession,
           client: str = Depends(client_id), owner: str | None = Depends(owner_of)) -> dict:
    campaign = create_campaign(session, body, client_id=client, commit=False, owner=owner)
    return built_then_committed(session, lambda: {**campaign_summary(campaign),
                                                  "estimate": campaign_estimate(session, campaign)}, CampaignSummary)


@router.get("", summary="List campaigns, newest (highest id) first; a page and the total", **typed(CampaignList))
def list_all(session: DbSession, status: CampaignStatus | None = Query(None), limit: CampaignLimit = 100,
             offset: Offset = 0) -> dict:
    rows, total = list_campaigns(session, status, limit=limit, offset=offset)
    return {"items": [campaign_summary(c) for c in rows], "total": total, "limit": limit, "offset": offset}


def _change(session: Session, campaign_id: int, who: Caller, action: str):
    """A campaign action by its owner or an administrator (403 otherwise), then the action."""
    who.require(get_campaign(session, campaign_id).owner, f"campaign {campaign_id}", ["path", "campaign_id"])
    return transition(session, campaign_id, action)


@router.get("/{campaign_id}", summary="Status: state, iteration, phase, run counts", **typed(CampaignSummary))
def status(campaign_id: CampaignId, session: DbSession) -> dict:
    campaign = get_campaign(session, campaign_id)
    return {**campaign_summary(campaign), "estimate": campaign_estimate(session, campaign)}


@router.post("/{campaign_id}/start", summary="draft -> running (409 otherwise)", responses=_STATE,
             **typed(CampaignSummary))
def start(campaign_id: CampaignId, session: DbSession, who: Caller = Depends(caller)) -> dict:
    return campaign_summary(_change(session, campaign_id, who, "start"))


@router.post("/{campaign_id}/pause", summary="running -> paused (409 otherwise); queued batteries keep running", responses=_STATE,
             **typed(CampaignSummary))
def pause(campaign_id: CampaignId, session: DbSession, who: Caller = Depends(caller)) -> dict:
    return campaign_summary(_change(session, campaign_id, who, "pause"))


@router.post("/{campaign_id}/resume", summary="paused -> running (409 otherwise)", responses=_STATE,
             **typed(CampaignSummary))
def resume(campaign_id: CampaignId, session: DbSession, who: Caller = Depends(caller)) -> dict:
    return campaign_summary(_change(session, campaign_id, who, "resume"))


@router.get("/{campaign_id}/iterations", summary="A page of the iterations with their parameters, design, runs and report",
            **typed(IterationList))
def iterations(campaign_id: CampaignId, session: DbSession, limit: IterationLimit = 20, offset: Offset = 0) -> dict:
    get_campaign(session, campaign_id)  # 404 for an unknown campaign, not an empty page
    rows, total = paged(session, CampaignIteration, where=[CampaignIteration.campaign_id == campaign_id],
                        order=(CampaignIteration.number, CampaignIteration.id), limit=limit, offset=offset)
    return {"items": [iteration_view(it) for it in rows], "total": total, "limit": limit, "offset": offset}


@router.post("/{campaign_id}/iterations", status_code=201,
             summary="Start the next iteration of a completed campaign (e.g. with a contact effect added)",
             responses=_STATE, **typed(CampaignSummary))
def add_iteration(campaign_id: CampaignId, body: IterationIn, session: DbSession, who: Caller = Depends(caller)) -> dict:
    who.require(get_campaign(session, campaign_id).owner, f"campaign {campaign_id}", ["path", "campaign_id"])
    return campaign_summary(next_iteration(session, campaign_id, body))


@router.post("/{campaign_id}/continue",
             summary="Take a completed automatic campaign up again with more iterations (409 when it stopped for "
                     "a reason more iterations do not change)", responses=_STATE, **typed(CampaignSummary))
def continue_(campaign_id: CampaignId, session: DbSession, body: ContinueIn | None = None,
              who: Caller = Depends(caller)) -> dict:
    who.require(get_campaign(session, campaign_id).owner, f"campaign {campaign_id}", ["path", "campaign_id"])
    return campaign_summary(continue_campaign(session, campaign_id, (body or ContinueIn()).more_iterations))


@router.post("/{campaign_id}/retry", summary="failed -> running: its failed batteries queued again, the others kept "
             "(409 otherwise)", responses=_STATE, **typed(CampaignSummary))
def retry(campaign_id: CampaignId, session: DbSession, who: Caller = Depends(caller)) -> dict:
    who.require(get_campaign(session, campaign_id).owner, f"campaign {campaign_id}", ["path", "campaign_id"])
    return campaign_summary(retry_campaign(session, campaign_id))


def _product(session: Session, campaign_id: CampaignId, number: int | None, attr: str, label: str):
    campaign = get_campaign(session, campaign_id)
    it = iteration(session, campaign, number)
    value = getattr(it, attr)
    if value is None:
        raise Conflict(f"campaign {campaign_id} iteration {it.number} has no {label} yet (phase {it.phase}, "
                       f"status {campaign.status})", ["path", "campaign_id"])
    return campaign, it, value


IterationQ = Query(None, ge=1, le=ID_MAX, description="iteration number; default the current one")


@router.get("/{campaign_id}/iterations/{number}", summary="One iteration", **typed(Iteration))
def one_iteration(campaign_id: CampaignId, number: IterationNumber, session: DbSession) -> dict:
    campaign = get_campaign(session, campaign_id)
    if not any(it.number == number for it in campaign.iterations):
        raise NotFound(f"campaign {campaign_id} has no iteration {number}", ["path", "number"])
    return iteration_view(iteration(session, campaign, number))


@router.get("/{campaign_id}/design", summary="The iteration's design: table, aliases, resolution", responses=_NOT_YET,
            **typed(CampaignDesign))
def design(session: DbSession, campaign_id: CampaignId, number: int | None = IterationQ) -> dict:
    _, it, value = _product(session, campaign_id, number, "design", "design")
    return {"iteration": it.number, **{k: v for k, v in value.items() if k != "doe"}}


@router.get("/{campaign_id}/models", summary="Fitted model per target response, with ANOVA", responses=_NOT_YET,
            **typed(CampaignModels))
def models(session: DbSession, campaign_id: CampaignId, number: int | None = IterationQ) -> dict:
    _, it, value = _product(session, campaign_id, number, "models", "fitted models")
    return {"iteration": it.number, "models": value}


@router.get("/{campaign_id}/optimum", summary="Optimised parameters, predictions with intervals, reachability", responses=_NOT_YET,
            **typed(CampaignOptimum))
def optimum(session: DbSession, campaign_id: CampaignId, number: int | None = IterationQ) -> dict:
    _, it, value = _product(session, campaign_id, number, "optimum", "optimum")
    return {"iteration": it.number, **value}


@router.get("/{campaign_id}/confirmation",
            summary="The batteries at the optimum, one per seed (after polishing on the batteries); the top level is "
                    "the first seed's", responses=_NOT_YET, **typed(Confirmation))
def confirmation(session: DbSession, campaign_id: CampaignId, number: int | None = IterationQ) -> dict:
    from calibration.polish import final_runs

    campaign = get_campaign(session, campaign_id)
    it = iteration(session, campaign, number)
    runs = final_runs(it)
    if not runs:
        raise Conflict(f"campaign {campaign_id} iteration {it.number} has no confirmation run yet "
                       f"(phase {it.phase})", ["path", "campaign_id"])

    def view(run) -> dict:
        return {"job_id": run.job_id, "status": run.status, "seed": run.seed, "responses": run.responses,
                "error": run.error}

    first = runs[0]
    return {"iteration": it.number, **view(first), "parameters": first.natural, "coded": first.coded,
            "runs": [view(r) for r in runs]}


@router.get("/{campaign_id}/report",
            summary="Per target: measured, predicted (interval), confirmed, residual, reachability", responses=_NOT_YET,
            **typed(ReportOut))
def report(session: DbSession, campaign_id: CampaignId, number: int | None = IterationQ) -> dict:
    from calibration.report import REACHABLE_LIMIT

    campaign, it, value = _product(session, campaign_id, number, "report", "report")
    # reachable_limit: the cutoff on reachability that decides "reachable" (the UI draws it)
    return {"campaign_id": campaign.id, "name": campaign.name, "material_id": campaign.material_id,
            "iteration": it.number, "evaluator": campaign.evaluator, "fidelity": campaign.fidelity,
            "reachable_limit": REACHABLE_LIMIT, **value}


@router.get("/{campaign_id}/diagnosis",
            summary="Which effect is missing: ranking (effect, LM, p, explained share, strength), alias groups, "
                    "fingerprints, what to measure next", responses=_NOT_YET, **typed(DiagnosisOut))
def diagnosis(session: DbSession, campaign_id: CampaignId, number: int | None = IterationQ) -> dict:
    campaign, it, value = _product(session, campaign_id, number, "report", "report")
    if "diagnosis" not in value:
        # a finished iteration without a diagnosis never runs one: say why, not "not done"
        verdict = value.get("verdict")
        if it.phase != Phase.DONE:
            reason = f"the diagnosis batteries are not done yet (phase {it.phase})"
        elif verdict == Verdict.CALIBRATED:
            reason = "the model reproduces the measurements; nothing to diagnose"
        else:
            reason = (f"the iteration finished ({verdict!r}) without one: the loop diagnoses only where a misfit "
                      "can be attributed (diagnose on, degrees of freedom left, and in automatic mode an "
                      "iteration the next one builds on)")
        raise Conflict(f"campaign {campaign_id} iteration {it.number} has no diagnosis: {reason}",
                       ["path", "campaign_id"])
    return {"campaign_id": campaign.id, "iteration": it.number, **value["diagnosis"]}


@router.get("/{campaign_id}/history",
            summary="Per iteration: effects, optimum, weighted error overall and per test with the noise band, "
                    "verdict, effect added next; per target the residual in each iteration", **typed(History))
def history(campaign_id: CampaignId, session: DbSession) -> dict:
    from calibration.history import history as loop_history

    campaign = get_campaign(session, campaign_id)
    return {"campaign_id": campaign.id, **loop_history(campaign.iterations)}


