"""Campaign endpoints: create, start/pause/resume (409 when illegal), and every product of a run."""
from __future__ import annotations

from fastapi import APIRouter, Depends, Query
from sqlalchemy.orm import Session

from service.campaigns.schemas import CampaignCreate, IterationIn
from service.campaigns.store import (campaign_summary, create_campaign, get_campaign, iteration, iteration_view,
                                     list_campaigns, next_iteration, transition)
from service.api.openapi import errors
from service.api.params import CampaignId, IterationNumber
from service.db import get_session
from service.errors import Conflict, NotFound
from service.security import client_id
from service.vocabulary import CampaignStatus

router = APIRouter(prefix="/campaigns", tags=["campaigns"])

_STATE = errors(409, c409="the campaign's status does not allow this")
_NOT_YET = errors(409, c409="the iteration has not produced this yet")


@router.post("", status_code=201, summary="Create a campaign (draft) for a material",
             responses=errors(404, c404="the material does not exist"))
def create(body: CampaignCreate, session: Session = Depends(get_session),
           client: str = Depends(client_id)) -> dict:
    return campaign_summary(create_campaign(session, body, client_id=client))


@router.get("", summary="List campaigns, newest first")
def list_all(status: CampaignStatus | None = Query(None), session: Session = Depends(get_session)) -> list[dict]:
    return [campaign_summary(c) for c in list_campaigns(session, status)]


@router.get("/{campaign_id}", summary="Status: state, iteration, phase, run counts")
def status(campaign_id: CampaignId, session: Session = Depends(get_session)) -> dict:
    return campaign_summary(get_campaign(session, campaign_id))


@router.post("/{campaign_id}/start", summary="draft -> running (409 otherwise)", responses=_STATE)
def start(campaign_id: CampaignId, session: Session = Depends(get_session)) -> dict:
    return campaign_summary(transition(session, campaign_id, "start"))


@router.post("/{campaign_id}/pause", summary="running -> paused (409 otherwise); queued batteries keep running", responses=_STATE)
def pause(campaign_id: CampaignId, session: Session = Depends(get_session)) -> dict:
    return campaign_summary(transition(session, campaign_id, "pause"))


@router.post("/{campaign_id}/resume", summary="paused -> running (409 otherwise)", responses=_STATE)
def resume(campaign_id: CampaignId, session: Session = Depends(get_session)) -> dict:
    return campaign_summary(transition(session, campaign_id, "resume"))


@router.get("/{campaign_id}/iterations", summary="All iterations with their parameters, design, runs and report")
def iterations(campaign_id: CampaignId, session: Session = Depends(get_session)) -> list[dict]:
    return [iteration_view(it) for it in get_campaign(session, campaign_id).iterations]


@router.post("/{campaign_id}/iterations", status_code=201,
             summary="Start the next iteration of a completed campaign (e.g. with a contact effect added)",
             responses=_STATE)
def add_iteration(campaign_id: CampaignId, body: IterationIn, session: Session = Depends(get_session)) -> dict:
    return campaign_summary(next_iteration(session, campaign_id, body))


def _product(session: Session, campaign_id: CampaignId, number: int | None, attr: str, label: str):
    campaign = get_campaign(session, campaign_id)
    it = iteration(session, campaign, number)
    value = getattr(it, attr)
    if value is None:
        raise Conflict(f"campaign {campaign_id} iteration {it.number} has no {label} yet (phase {it.phase}, "
                       f"status {campaign.status})", ["path", "campaign_id"])
    return campaign, it, value


IterationQ = Query(None, ge=1, le=2**63 - 1, description="iteration number; default the current one")


@router.get("/{campaign_id}/iterations/{number}", summary="One iteration")
def one_iteration(campaign_id: CampaignId, number: IterationNumber, session: Session = Depends(get_session)) -> dict:
    campaign = get_campaign(session, campaign_id)
    if not any(it.number == number for it in campaign.iterations):
        raise NotFound(f"campaign {campaign_id} has no iteration {number}", ["path", "number"])
    return iteration_view(iteration(session, campaign, number))


@router.get("/{campaign_id}/design", summary="The iteration's design: table, aliases, resolution", responses=_NOT_YET)
def design(campaign_id: CampaignId, number: int | None = IterationQ, session: Session = Depends(get_session)) -> dict:
    _, it, value = _product(session, campaign_id, number, "design", "design")
    return {"iteration": it.number, **{k: v for k, v in value.items() if k != "doe"}}


@router.get("/{campaign_id}/models", summary="Fitted model per target response, with ANOVA", responses=_NOT_YET)
def models(campaign_id: CampaignId, number: int | None = IterationQ, session: Session = Depends(get_session)) -> dict:
    _, it, value = _product(session, campaign_id, number, "models", "fitted models")
    return {"iteration": it.number, "models": value}


@router.get("/{campaign_id}/optimum", summary="Optimised parameters, predictions with intervals, reachability", responses=_NOT_YET)
def optimum(campaign_id: CampaignId, number: int | None = IterationQ, session: Session = Depends(get_session)) -> dict:
    _, it, value = _product(session, campaign_id, number, "optimum", "optimum")
    return {"iteration": it.number, **value}


@router.get("/{campaign_id}/confirmation",
            summary="The batteries at the optimum, one per seed (after polishing on the batteries); the top level is "
                    "the first seed's", responses=_NOT_YET)
def confirmation(campaign_id: CampaignId, number: int | None = IterationQ, session: Session = Depends(get_session)) -> dict:
    from service.campaigns.polish import final_runs

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
            summary="Per target: measured, predicted (interval), confirmed, residual, reachability", responses=_NOT_YET)
def report(campaign_id: CampaignId, number: int | None = IterationQ, session: Session = Depends(get_session)) -> dict:
    from service.campaigns.report import REACHABLE_LIMIT

    campaign, it, value = _product(session, campaign_id, number, "report", "report")
    # reachable_limit: the cutoff on reachability that decides "reachable" (the UI draws it)
    return {"campaign_id": campaign.id, "name": campaign.name, "material_id": campaign.material_id,
            "iteration": it.number, "evaluator": campaign.evaluator, "fidelity": campaign.fidelity,
            "reachable_limit": REACHABLE_LIMIT, **value}


@router.get("/{campaign_id}/diagnosis",
            summary="Which effect is missing: ranking (effect, LM, p, explained share, strength), alias groups, "
                    "fingerprints, what to measure next", responses=_NOT_YET)
def diagnosis(campaign_id: CampaignId, number: int | None = IterationQ,
              session: Session = Depends(get_session)) -> dict:
    campaign, it, value = _product(session, campaign_id, number, "report", "report")
    if "diagnosis" not in value:
        reason = ("the model reproduces the measurements; nothing to diagnose"
                  if value.get("verdict") == "calibrated" and it.phase != "diagnosis"
                  else f"the diagnosis batteries are not done (phase {it.phase})")
        raise Conflict(f"campaign {campaign_id} iteration {it.number} has no diagnosis: {reason}",
                       ["path", "campaign_id"])
    return {"campaign_id": campaign.id, "iteration": it.number, **value["diagnosis"]}


@router.get("/{campaign_id}/history",
            summary="Per iteration: effects, optimum, weighted error overall and per test with the noise band, "
                    "verdict, effect added next; per target the residual in each iteration")
def history(campaign_id: CampaignId, session: Session = Depends(get_session)) -> dict:
    from calibration.stats import weighted_rms
    from service.campaigns.analysis import active_effects

    campaign = get_campaign(session, campaign_id)
    done = [it for it in sorted(campaign.iterations, key=lambda i: i.number) if it.report]
    entries, previous, targets, plan = [], set(), {}, {}
    for it in done:
        report = it.report
        effects = sorted(active_effects(it.parameters))
        # in automatic mode an iteration is built on a named base (the one before, or an earlier one when
        # an added effect was rejected or its range widened): what it added is relative to that base
        base = next((b for b in done if b.number == plan.get("next_base")), None)
        if base is not None:
            previous = set(active_effects(base.parameters))
        lof = report.get("lack_of_fit") or {}
        diag = report.get("diagnosis")
        entries.append({
            "number": it.number, "effects": effects, "added_effect": sorted(set(effects) - previous) or None,
            "optimum": report.get("optimum"), "parameter_std": (it.optimum or {}).get("parameter_std"),
            "chi2": lof.get("statistic"), "chi2_per_dof": lof.get("chi2_per_dof"), "dof": lof.get("dof"),
            "noise_band": lof.get("noise_band"), "lack_of_fit_p": lof.get("p_value"),
            # once the diagnosis ran: Holm over the lack of fit and the candidates' directed test
            "adequacy_p": (report.get("adequacy") or {}).get("p_value"),
            "directed_p": ((report.get("adequacy") or {}).get("directed") or {}).get("p_value"),
            "per_test": {t["test"]: t["chi2"] for t in report.get("tests", [])},
            # the weighted error the acceptance criteria halve: RMS of the targets' standardised residuals
            "weighted_rms": _finite(weighted_rms([row.get("standardised_residual") for row in report.get("targets", [])
                                                  if row.get("status") == "modelled"])),
            "verdict": report.get("verdict"),
            "top_effect": (diag or {}).get("ranking", [{}])[0].get("effect") if diag and diag.get("ranking") else None,
            # automatic mode: whether this iteration's added effect was kept, and why the loop stopped
            "decision": (report.get("automatic") or {}).get("decision"),
            "stop_reason": (report.get("automatic") or {}).get("stop_reason"),
            "range_widened": bool(plan.get("widened")),
        })
        plan = report.get("automatic") or {}
        previous = set(effects)
        for row in report.get("targets", []):
            if row.get("status") != "modelled":
                continue
            label = row.get("response") or row["quantity"]
            targets.setdefault(label, {"test": row["test"], "quantity": row["quantity"],
                                       "condition": row["condition"], "residuals": {}})
            targets[label]["residuals"][str(it.number)] = row.get("standardised_residual")
    for a, b in zip(entries, entries[1:]):
        a["effect_added_next"] = b["added_effect"]
    if entries:
        entries[-1]["effect_added_next"] = None
    return {"campaign_id": campaign.id, "iterations": entries, "targets": targets}


def _finite(value: float) -> float | None:
    return value if value == value else None  # NaN (no modelled target) -> null
