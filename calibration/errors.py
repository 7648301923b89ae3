"""What the loop raises, with the setting it concerns, so each caller words it its own way (the
service as a 422 or 409 naming the field, a notebook as the exception itself)."""
from __future__ import annotations


class LoopFailed(Exception):
    """A step cannot succeed (a battery failed, no target can be modelled): the loop stops failed."""


class SettingsError(ValueError):
    """A setting the loop cannot work with; ``field`` is its dotted path (``design.generators``),
    ``conflict`` says it clashes with the loop's state (e.g. an effect that is already a factor)
    rather than being invalid in itself."""

    def __init__(self, message: str, field: str | None = None, *, conflict: bool = False):
        super().__init__(message)
        self.message = message
        self.field = field
        self.conflict = conflict
