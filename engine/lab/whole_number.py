"""An integer field of an input model that also takes a whole float (2.0), in a module of its own so that the
rig records (``engine.lab.rigs``) and the job spec (``engine.lab.spec``), which embeds a rig, share it without
importing each other.

JSON has one number type and JSON Schema's "integer" admits 2.0, which is what a client computing a seed or
a count in floating point sends; strict mode alone refused it ("Input should be a valid integer") while the
published schema allowed it. Booleans, strings and fractions are still refused.
"""
from __future__ import annotations

from typing import Annotated, Any

from pydantic import BeforeValidator, Field


def _whole_float_to_int(value: Any) -> Any:
    """2.0 -> 2; anything else (2.5, true, "2") left for the strict check to refuse."""
    return int(value) if type(value) is float and value.is_integer() else value


WholeNumber = Annotated[int, BeforeValidator(_whole_float_to_int)]


def bounded_whole_number(ge: int, le: int):
    """A ``WholeNumber`` within [ge, le] whose bounds the JSON schema states. Why not ``WholeNumber | None =
    Field(None, ge=..., le=...)``: on a nullable type with a before-validator pydantic published the bounds as
    "ge"/"le", keys JSON Schema does not know, so schema-valid clients (and the fuzz) sent 2037 replicates to a
    field that refuses more than 1000. Inside the union, before the validator, they are "minimum"/"maximum"."""
    return Annotated[int, Field(ge=ge, le=le), BeforeValidator(_whole_float_to_int)]
