"""The material card from the database: of a campaign's calibrated iteration, of a material imported
from a card, and the import itself (card -> material with fixed parameters).

An imported material keeps what the card says in the places demcal keeps such things: its name,
description and source in the material's columns, the measurements as measurement rows (SI, with their
replicates), and the rest under ``direct_estimates["material_card"]``: the fixed micro parameters, the
rig, the calibration's provenance and the result per measurement. Its card is rebuilt from those
(``material_card``): the particles, contact law and rig are derived again from the parameters, so the
round trip card -> material -> card checks the derivation as well as the storage.
"""
from __future__ import annotations

from typing import Any

from sqlalchemy.orm import Session

from engine.lab.resolution import is_preset
from service.errors import Conflict, Invalid, NotFound
from service.export import card as cards

STORED_KEY = "material_card"


def demcal_version() -> str:
    from service.api.health import _version

    return _version()


def calibrated_iteration(campaign, number: int | None = None):
    """The iteration whose report the card is built from: ``number``, else the model the loop keeps as of its
    latest report (``calibration.automatic.kept_number``: an added effect rejected leaves the iteration it was
    built on; a page or LIGGGHTS input must not hand on the rejected one); a 409 when there is none (a card
    states calibrated values, and there are none before the report)."""
    from calibration.automatic import kept_number

    done = sorted((it for it in campaign.iterations if it.report), key=lambda it: it.number)
    if number is not None:
        it = next((it for it in campaign.iterations if it.number == number), None)
        if it is None:
            raise NotFound(f"campaign {campaign.id} has no iteration {number}", ["query", "number"])
        if not it.report:
            raise Conflict(f"campaign {campaign.id} iteration {number} is not calibrated yet (phase {it.phase}): "
                           "its report comes first", ["path", "campaign_id"])
        return it
    if not done:
        current = next((it for it in campaign.iterations if it.number == campaign.current_iteration), None)
        raise Conflict(f"campaign {campaign.id} is not calibrated yet (status {campaign.status}, phase "
                       f"{current.phase if current else '-'}): a material card states calibrated values, which "
                       "come with the first iteration's report", ["path", "campaign_id"])
    kept = kept_number(done[-1].number, done[-1].report)
    return next((it for it in done if it.number == kept), done[-1])


def campaign_card(session: Session, campaign_id: int, number: int | None = None) -> dict[str, Any]:
    from service.campaigns.store import get_campaign
    from service.materials.store import get_material, material_dict

    campaign = get_campaign(session, campaign_id)
    it = calibrated_iteration(campaign, number)
    material = get_material(session, campaign.material_id)
    view = material_dict(material)
    config, settings = campaign.config or {}, it.parameters or {}
    report, factors = without_turned_off(it.number, it.report, settings.get("factors", config.get("factors") or []))
    return cards.build_card(
        material=view, measurements=view["measurements"],
        campaign={"id": campaign.id, "name": campaign.name, "test": config.get("test", "battery"),
                  # the iteration's own settings (an added effect, a narrowed range, a resolution), else the campaign's
                  "evaluator": settings.get("evaluator", campaign.evaluator),
                  **card_set_up(settings.get("lab") or config, settings.get("fidelity", campaign.fidelity)),
                  "options": settings.get("options", config.get("options") or {}),
                  "factors": factors},
        iteration=it.number, report=report, parameter_std=(it.optimum or {}).get("parameter_std"),
        demcal_version=demcal_version())


def without_turned_off(number: int, report: dict[str, Any], factors: list[dict[str, Any]]):
    """(report, factors) for the card of iteration ``number``: when the automatic mode kept this iteration as
    the base model refitted because the fit put the contact effect it added at its off strength
    (``calibration.automatic.turned_off``), that effect leaves the card (its parameters, its factor, its row
    of calibrated values) and the meaning says so. Why: a surface energy of 3e-12 J/m2 handed to LIGGGHTS is a
    model with an effect switched on in name only, and a reader of the card would take it as found. A particle
    factor (an aspect ratio of 1) is the base model as it stands and stays."""
    record = (report or {}).get("automatic") or {}
    decision = record.get("decision") or {}
    if not (decision.get("turned_off") and decision.get("effect") and record.get("kept_iteration") == number):
        return report, factors
    prefix = f"effects.{decision['effect']}."
    dropped = {k: v for k, v in (report.get("optimum") or {}).items() if k.startswith(prefix)}
    if not dropped:
        return report, factors
    keep = lambda names: {k: v for k, v in (names or {}).items() if not k.startswith(prefix)}  # noqa: E731
    values = ", ".join(f"{k.removeprefix(prefix)} {v:.3g}" for k, v in dropped.items())
    note = (f"{decision['effect']} was fitted at its off strength ({values}) and is left out of this card: "
            "the model kept is the base model refitted.")
    meaning = f"{report['meaning']} {note}" if report.get("meaning") else note
    intervals = report.get("intervals") or {}
    return ({**report, "optimum": keep(report.get("optimum")), "fixed_parameters": keep(report.get("fixed_parameters")),
             "meaning": meaning, "intervals": {**intervals, "parameters": keep(intervals.get("parameters")),
                                               "trades": [t for t in intervals.get("trades") or []
                                                          if not any(n.startswith(prefix) for n in t["parameters"])]}},
            [f for f in factors if not f["name"].startswith(prefix)])


def card_set_up(lab: dict[str, Any], fidelity: str) -> dict[str, Any]:
    """The card's rig section's set-up from where an iteration ran (``calibration.reuse.lab_json``, or a campaign
    configuration stored before iterations recorded it): the preset, or the resolution with its factor resolved
    (a coarse target particle count becomes the factor it chose), the rig record and the material's particles."""
    from pydantic import TypeAdapter

    from engine.lab.resolution import ResolutionIn, material_setup, parsed
    from engine.lab.rigs import Rig
    from engine.particles.description import Particles

    resolution = TypeAdapter(ResolutionIn | None).validate_python(lab.get("resolution"))
    if is_preset(resolution):
        return {"fidelity": resolution or fidelity}
    rig, particles = Rig.model_validate(lab["rig"]), Particles.model_validate(lab["particles"])
    setup, _ = material_setup(rig, particles, resolution)
    return {"fidelity": None, "resolution": parsed(resolution).mode, "scale_factor": float(setup.scale_factor),
            "rig_record": rig.model_dump(mode="json"), "material_particles": particles.model_dump(mode="json")}


def material_card(session: Session, material_id: int) -> dict[str, Any]:
    """The card of a material imported from one (409 for any other material: it has no calibrated values)."""
    from service.materials.store import get_material, material_dict

    material = get_material(session, material_id)
    if material is None:
        raise NotFound(f"material {material_id} not found", ["path", "material_id"])
    stored = (material.direct_estimates or {}).get(STORED_KEY)
    if not stored:
        raise Conflict(f"material {material_id} ({material.name!r}) was not imported from a material card, so it "
                       "has no calibrated parameters; export the card of a campaign that calibrated it "
                       "(GET /api/v1/campaigns/{id}/material-card)", ["path", "material_id"])
    view = material_dict(material)
    try:
        return _rebuilt(view, stored)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:  # written by hand into direct_estimates
        raise Conflict(f"material {material_id}'s direct_estimates.{STORED_KEY} is not what an import stores "
                       f"({type(exc).__name__}: {str(exc).splitlines()[0][:200]}); import the card again", ["path", "material_id"]) from None


def _rebuilt(view: dict[str, Any], stored: dict[str, Any]) -> dict[str, Any]:
    from engine.lab.spec import MicroParameters

    params = MicroParameters.model_validate(stored["fixed_parameters"])
    rig = stored["rig"]
    card = {
        "card_version": stored["card_version"], "format": cards.CARD_FORMAT, "demcal_version": stored["demcal_version"],
        "material": {"name": view["name"], "description": view["description"], "source": view["source"]},
        **cards.physics_sections(params, rig),
        "calibration": stored["calibration"],
        "measurements": [cards.measurement_card(m, _result_of(m, stored["results"])) for m in view["measurements"]],
    }
    return cards.canonical(card)


def _result_of(measurement: dict[str, Any], results: list[dict[str, Any]]):
    """The stored result of this measurement, found by its key (a measurement deleted or added since the
    import shifts no other's result); None for one the card did not have."""
    from calibration.keys import ResponseKey

    key = ResponseKey.from_record(measurement)
    return next((r["result"] for r in results if ResponseKey.from_record(r).matches(key)), None)


def _loc(index: int, field) -> list:
    """``["body", "measurements", 0, "values", 1]``: list indices as numbers, as FastAPI's own 422s give them."""
    parts = field if isinstance(field, (list, tuple)) else str(field or "").split(".")
    parts = [p for p in parts if p not in ("", "body")]
    return ["body", "measurements", index, *(int(p) if isinstance(p, str) and p.isdigit() else p for p in parts)]


def _si_unit(test: str, quantity_name: str) -> str | None:
    """The quantity's SI unit, or None for an unknown test or quantity (MeasurementIn names those)."""
    from engine.lab.registry import quantity

    try:
        return quantity(test, quantity_name).unit
    except (KeyError, ValueError):
        return None


def import_card(session: Session, data: Any, name: str | None = None):
    """A new material with the card's fixed parameters and measurements (not committed); 422 naming the
    card's field when it is not a card demcal can build, 409 when the name is taken."""
    from service.materials.schemas import MeasurementIn
    from service.materials.store import add_measurement, find_by_name
    from service.models.material import Material

    try:
        card = cards.validate(data)
        params = cards.micro_parameters(card)
    except cards.CardError as exc:
        raise Invalid(str(exc), exc.field) from None
    name = name or card.material.name
    if find_by_name(session, name) is not None:
        raise Conflict(f"a material named {name!r} exists; import under another name (?name=... or --name)", "name")
    stored = {"card_version": card.card_version, "demcal_version": card.demcal_version,
              "fixed_parameters": params.model_dump(mode="json"),
              "rig": cards.rig_where(card.rig.model_dump(mode="json")),
              "calibration": card.calibration.model_dump(mode="json") if card.calibration is not None else None,
              # by measurement key, as the calibration matches them
              "results": [{"test": m.test, "quantity": m.quantity, "condition": m.condition,
                           "result": m.result.model_dump(mode="json") if m.result is not None else None}
                          for m in card.measurements]}
    material = Material(name=name, description=card.material.description, source=card.material.source,
                        bundled=False, direct_estimates={STORED_KEY: stored})
    session.add(material)
    for index, m in enumerate(card.measurements):
        si_unit = _si_unit(m.test, m.quantity)
        if si_unit is not None and m.unit != si_unit:
            raise Invalid(f"measurements.{index}.unit: {m.unit!r}; a card states measurements in SI, {si_unit!r}",
                          _loc(index, "unit"))
        try:
            measurement = MeasurementIn.model_validate({
                "test": m.test, "quantity": m.quantity, "unit": m.unit, "values": m.values,
                "condition": m.condition, "reported_replicates": m.reported_replicates,
                "standard_uncertainty": m.stated_uncertainty, "source": m.source})
            add_measurement(session, material, measurement)
        except Invalid as exc:
            raise Invalid(f"measurements.{index}: {exc.message}", _loc(index, exc.field)) from None
        except ValueError as exc:  # pydantic's ValidationError
            errors = getattr(exc, "errors", None)
            first = errors(include_url=False)[0] if errors else {"loc": (), "msg": str(exc)}
            where = ".".join(str(p) for p in first.get("loc", ()))
            raise Invalid(f"measurements.{index}.{where}: {first.get('msg')}", _loc(index, where)) from None
    return material
