"""The error a lab check raises when a job spec cannot run: it carries the field to change.

Why a field attribute: the service answers such a spec with a 422 whose ``loc`` names the field; with the
field on the error it is read, not parsed back out of the message.
"""
from __future__ import annotations


class SpecFieldError(ValueError):
    """``field`` is the dotted path in ``JobSpec`` (``options.cct_cycles``); ``message`` says why."""

    def __init__(self, field: str, message: str):
        super().__init__(f"{field}: {message}")
        self.field = field
        self.message = message
