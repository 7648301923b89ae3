"""Replicate values as people type them: the one rule for a list of numbers given as text.

Why a rule of its own: "1397,8" typed into a list field was stored as two replicates, 1397 and 8, with
no word; a comma is a decimal separator in much of Europe and a list or thousands separator elsewhere.
The rule, which the CLI (``demcal material add-measurement --values``) applies here and the web page
applies in its own script (the page has no Python), is:

* values are separated by semicolons, whitespace or newlines, never by commas;
* a number takes a decimal point, or instead a single decimal comma where that reading is the only
  one: "1397,8" is 1397.8 and "0,397" is 0.397, but "1,397" (1.397, or 1397 with a thousands
  separator?) is refused, as is any number with two commas or both a comma and a point;
* anything else (an empty list, a word, nan or inf) is refused; every refusal names the field.

The API takes JSON numbers, which need none of this.
"""
from __future__ import annotations

import math
import re

SEPARATORS = re.compile(r"[;\s]+")
_NUMBER = re.compile(r"[+-]?(?:\d+(?:[.,]\d*)?|[.,]\d+)(?:[eE][+-]?\d+)?")
# a comma that could be a thousands separator: 1-3 leading digits (not just zeros), then exactly three
_THOUSANDS = re.compile(r"[+-]?0*[1-9]\d{0,2},\d{3}")


class ReplicateError(ValueError):
    """A list that cannot be read as written; the message names the field and the value."""


def parse_number(text: str, field: str) -> float:
    """One number, with a decimal point or an unambiguous decimal comma (see the module's rule)."""
    if not _NUMBER.fullmatch(text):
        if text.count(",") > 1 or ("," in text and "." in text):
            raise ReplicateError(f"{field}: {text!r} has a thousands separator or mixes ',' and '.'; write "
                                 "the number without grouping and with one decimal separator, e.g. 1397.8")
        raise ReplicateError(f"{field}: {text!r} is not a number")
    if _THOUSANDS.fullmatch(text):
        whole, frac = text.split(",")
        raise ReplicateError(f"{field}: {text!r} is ambiguous (a decimal comma, {whole}.{frac}, or a thousands "
                             f"separator, {whole}{frac}?); write it with a point or without the comma")
    value = float(text.replace(",", "."))
    if not math.isfinite(value):
        raise ReplicateError(f"{field}: {text!r} is not a finite number")
    return value


def parse_replicates(text: str, field: str = "values") -> list[float]:
    """The replicate values in ``text``, in order; ReplicateError naming ``field`` if any cannot be read."""
    tokens = [t for t in SEPARATORS.split(text) if t]
    if not tokens:
        raise ReplicateError(f"{field}: no values (separate replicates with ';', spaces or new lines)")
    return [parse_number(token, field) for token in tokens]


__all__ = ["ReplicateError", "parse_number", "parse_replicates"]
