"""Plausibility: a value inside its physical bound but outside what granular materials measure is stored with a
warning that names the likely slip.

Why warnings and not refusals: an unusual material is possible, a porosity of 1.7 is not. The bounds
(``engine.lab.bounds``) refuse the impossible; what they let through can still be a number typed in the wrong
unit, and such a number costs a day: it is stored, becomes a target, and the calibration reports it "out of
reach". The ranges are declared once, beside each bound (a quantity's ``Typical`` in the lab-test registry,
a condition's in ``CONDITION_TYPICAL``, a micro parameter's in its ``MicroParameters`` annotation); this
module only reads them and words the warning, e.g.

    fill bulk_density_kg_m3 = 1.3967 kg/m3 is below the bulk densities of dry granular materials
    (50 to 4,000 kg/m3; ...); was it g/cm3 or t/m3, 1,000 times more (1,397 kg/m3)?

The likely slip is the accepted unit (``engine.lab.units``) or declared reading (``Typical.readings``) that
puts the typed number back inside the range, nearest its middle. Everything here is a pure function of
plain values, so the service (at entry) and the database-free calibration loop (in each report) give the
same words.
"""
from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

from engine.lab.bounds import CONDITION_TYPICAL, Bound, Typical
from engine.lab.units import canonical_unit, condition_si_unit, unit_factors, UnitError

# Micro-parameter names end with their SI unit too, with suffixes no condition uses; longest first.
_PARAMETER_SUFFIXES = (("_kg_m3", "kg/m3"), ("_n_per_m", "N/m"))


def _number(value: float, digits: int = 6) -> str:
    """8,690 and 1.3967 as people write them (``digits`` significant); very large or small numbers in
    exponent form."""
    if value == 0:
        return "0"
    if not 1e-3 <= abs(value) < 1e6:
        return f"{value:.3g}"
    decimals = max(0, digits - 1 - math.floor(math.log10(abs(value))))
    text = f"{value:,.{decimals}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def _in(value: float, unit: str, digits: int = 6) -> str:
    """A value with its unit; a pure number ("1") alone."""
    return _number(value, digits) + ("" if unit == "1" else f" {unit}")


def _times(ratio: float) -> str:
    """A unit slip's factor as a person says it, when it is a power of ten: ", 1,000 times more"."""
    exponent = math.log10(ratio)
    if ratio <= 0 or abs(exponent - round(exponent)) > 1e-9 or round(exponent) == 0:
        return ""
    return f", {_number(10.0 ** abs(round(exponent)))} times {'more' if exponent > 0 else 'less'}"


def _distance(typical: Typical, value: float) -> float:
    """How far from the middle of the range: in decades for a positive range, in range widths otherwise."""
    if typical.low > 0 and value > 0:
        return abs(math.log10(value / math.sqrt(typical.low * typical.high)))
    return abs(value - (typical.low + typical.high) / 2) / (typical.high - typical.low)


def _likely_slips(value_si: float, si_unit: str, typical: Typical, input_unit: str | None,
                  bound: Bound | None) -> list[str]:
    """What the typed number was probably meant as: the other unit that puts it nearest the middle of the
    range (units of one factor named together: g/cm3 or t/m3), then the nearest declared reading."""

    def fits(meant: float) -> bool:
        return math.isfinite(meant) and typical.contains(meant) and (bound is None or bound.contains(meant))

    factors = unit_factors(si_unit)
    given = canonical_unit(input_unit) if input_unit else si_unit
    typed = value_si / factors.get(given, 1.0)
    by_factor: dict[float, list[str]] = {}
    for unit, factor in factors.items():
        if unit != given and fits(typed * factor):
            by_factor.setdefault(factor, []).append(unit)
    slips: list[tuple[float, str]] = []
    if by_factor:
        factor = min(by_factor, key=lambda f: _distance(typical, typed * f))
        meant = typed * factor
        slips.append((_distance(typical, meant), f"{' or '.join(by_factor[factor])}{_times(meant / value_si)} "
                                                 f"({_in(meant, si_unit, 4)})"))
    readings = [(r, r.to_si(typed)) for r in typical.readings]
    readings = [(r, meant) for r, meant in readings if fits(meant)]
    if readings:
        reading, meant = min(readings, key=lambda rm: _distance(typical, rm[1]))
        slips.append((_distance(typical, meant), f"{reading.meaning} ({_in(meant, si_unit, 4)})"))
    return [text for _, text in sorted(slips)]


def slip_warning(label: str, value_si: float, si_unit: str, typical: Typical | None, *,
                 input_unit: str | None = None, bound: Bound | None = None) -> str | None:
    """None inside the typical range (or where none is declared); else the warning for ``label`` = value.

    ``input_unit`` is the unit the number was typed in (default SI): 8.6 GPa entered as 8,600,000 kPa was
    probably meant in Pa, which only the typed number shows."""
    if typical is None or not math.isfinite(value_si) or typical.contains(value_si):
        return None
    side = "below" if value_si < typical.low else "above"
    text = (f"{label} = {_in(value_si, si_unit)} is {side} {typical.what} "
            f"({_number(typical.low)} to {_in(typical.high, si_unit)}; {typical.source})")
    slips = _likely_slips(value_si, si_unit, typical, input_unit, bound)
    if slips:
        return f"{text}; was it {', or '.join(slips)}?"
    return f"{text}; check the value and its unit"


def measurement_warnings(test: str, quantity: str, values: Iterable[float], condition: Mapping[str, float] | None = None,
                         *, input_unit: str | None = None, measurement_id: int | None = None) -> list[str]:
    """Warnings of one measurement (SI values and conditions, as stored): its mean, or each replicate
    outside the range when the mean is inside (a decimal comma split into two replicates), then its
    conditions (typed in SI: the stored row keeps no condition units)."""
    from engine.lab.registry import quantity as declared_quantity

    try:
        declared = declared_quantity(test, quantity)
    except ValueError:  # a stored row of a quantity no longer declared: no range to hold it against
        return []

    def label(detail: str = "") -> str:
        inner = f"{test} {quantity}{detail}"
        return f"measurement {measurement_id} ({inner})" if measurement_id is not None else inner

    values = [float(v) for v in values if v is not None and math.isfinite(v)]
    warnings: list[str] = []
    if values:
        mean = math.fsum(v / len(values) for v in values)  # each share first: 1e308 twice does not overflow
        found = slip_warning(label("" if len(values) == 1 else f", mean of {len(values)} replicates"), mean,
                             declared.unit, declared.typical, input_unit=input_unit, bound=declared.bound)
        if found is not None:
            warnings.append(found)
        elif len(values) > 1:
            for index, value in enumerate(values):
                found = slip_warning(label(f", value {index + 1}"), value, declared.unit, declared.typical,
                                     input_unit=input_unit, bound=declared.bound)
                if found is not None:
                    warnings.append(found)
    for cname, cvalue in (condition or {}).items():
        if cvalue is None:
            continue
        try:
            si = condition_si_unit(cname)
        except UnitError:
            continue
        found = slip_warning(f"{label()} condition {cname}", float(cvalue), si, CONDITION_TYPICAL.get(cname))
        if found is not None:
            warnings.append(found)
    return warnings


def record_warnings(records: Iterable[Any]) -> list[str]:
    """``measurement_warnings`` of each record: the loop's ``Measured`` (its ``key``), a stored row or a dict
    with test, quantity, condition, values and, if known, input_unit and id."""
    warnings: list[str] = []
    for record in records:
        get = record.get if isinstance(record, Mapping) else (lambda k, r=record: getattr(r, k, None))
        key = get("key")
        test, quantity = (key.test, key.quantity) if key is not None else (get("test"), get("quantity"))
        condition = key.condition_dict if key is not None else get("condition")
        warnings += measurement_warnings(test, quantity, get("values") or (), condition,
                                         input_unit=get("input_unit") or None, measurement_id=get("id"))
    return warnings


def _si_unit_of_field(name: str) -> str:
    for suffix, unit in _PARAMETER_SUFFIXES:
        if name.endswith(suffix):
            return unit
    try:
        return condition_si_unit(name)
    except UnitError:
        return "1"  # coefficients and ratios


def _typical_of(model: type, name: str) -> Typical | None:
    field = model.model_fields.get(name)
    return None if field is None else next((m for m in field.metadata if isinstance(m, Typical)), None)


def _field_warnings(model: type, values: Mapping[str, Any], prefix: str) -> list[str]:
    warnings: list[str] = []
    for name, value in (values or {}).items():
        typical = _typical_of(model, name)
        if typical is None or value is None:
            continue
        unit = _si_unit_of_field(name)
        items = list(enumerate(value)) if isinstance(value, (list, tuple)) else [(None, value)]
        for index, item in items:
            if isinstance(item, bool) or not isinstance(item, (int, float)):
                continue
            where = f"{prefix}.{name}" + ("" if index is None else f"[{index}]")
            found = slip_warning(where, float(item), unit, typical)
            if found is not None:
                warnings.append(found)
    return warnings


def parameter_warnings(parameters: Mapping[str, Any], prefix: str = "parameters") -> list[str]:
    """Micro parameters (``MicroParameters`` fields, SI) outside their typical ranges."""
    from engine.lab.spec import MicroParameters

    return _field_warnings(MicroParameters, parameters, prefix)


def options_warnings(options: Mapping[str, Any], prefix: str = "options") -> list[str]:
    """Test options (``TestOptions`` fields, SI) outside their typical ranges: the DST's normal stresses."""
    from engine.lab.spec import TestOptions

    return _field_warnings(TestOptions, options, prefix)


def factor_warnings(factors: Iterable[Any], prefix: str = "factors") -> list[str]:
    """Each end of each factor range (SI, a ``MicroParameters`` field) outside its typical range."""
    from engine.lab.spec import MicroParameters

    warnings: list[str] = []
    for index, factor in enumerate(factors):
        get = factor.get if isinstance(factor, Mapping) else (lambda k, f=factor: getattr(f, k, None))
        name = get("name")
        typical = _typical_of(MicroParameters, name)
        if typical is None:
            continue
        for end in ("low", "high"):
            found = slip_warning(f"{prefix}[{index}] {name} {end}", float(get(end)), _si_unit_of_field(name), typical)
            if found is not None:
                warnings.append(found)
    return warnings


def settings_warnings(settings: Mapping[str, Any]) -> list[str]:
    """A calibration's factor ranges, fixed parameters and test options (a campaign's or the loop's settings
    as a dict) outside their typical ranges."""
    return (factor_warnings(settings.get("factors") or ())
            + parameter_warnings(settings.get("fixed_parameters") or {}, "fixed_parameters")
            + options_warnings(settings.get("options") or {}))
