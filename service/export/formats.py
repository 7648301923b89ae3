"""The export formats of a calibrated material: name -> media type, file suffix and a function of the card.

Why a registry: every format is written from the material card alone (``service.export.card``), so a new
format (the LIGGGHTS include, say) is one function ``(card: dict) -> str`` and one entry here; the API
(``GET /api/v1/campaigns/{id}/export?format=NAME``) and the CLI (``demcal campaign export ID --format
NAME``) list and serve every entry without further code.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from service.export.card import dump_json, dump_yaml


@dataclass(frozen=True)
class ExportFormat:
    name: str
    media_type: str
    suffix: str  # of the file the CLI writes and the API suggests (Content-Disposition)
    render: Callable[[dict], str]  # the material card (a dict of MaterialCard's schema) -> the file's text
    description: str


FORMATS: dict[str, ExportFormat] = {}


def register(fmt: ExportFormat) -> None:
    FORMATS[fmt.name] = fmt


register(ExportFormat("card", "application/yaml", ".card.yaml", dump_yaml,
                      "the neutral material card, YAML (docs/export.md)"))
register(ExportFormat("card-json", "application/json", ".card.json", dump_json,
                      "the neutral material card, JSON"))


def liggghts_include(card: dict) -> str:
    """The card's material as a LIGGGHTS-PUBLIC 3.8.0 input include (calibration.export.liggghts): its
    header lists every conversion made and what LIGGGHTS cannot express exactly."""
    from calibration.export.liggghts import render
    from calibration.export.material import from_micro_parameters
    from service.export.card import micro_parameters, rig_where, set_up, validate

    model = validate(card)
    params = micro_parameters(model)
    where = rig_where(model.rig.model_dump(mode="json"))
    return render(from_micro_parameters(params, model.rig.fidelity or model.rig.resolution,
                                        setup=set_up(where, params))).text


register(ExportFormat("liggghts", "text/plain", ".liggghts", liggghts_include,
                      "LIGGGHTS-PUBLIC 3.8.0 input include: atom types, property/global blocks, pair style, "
                      "multisphere templates; every conversion in its header (docs/export.md)"))


def get(name: str) -> ExportFormat:
    try:
        return FORMATS[name]
    except KeyError:
        raise ValueError(f"unknown export format {name!r}; known: {', '.join(sorted(FORMATS))}") from None


def names() -> list[str]:
    return sorted(FORMATS)
