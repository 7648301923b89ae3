"""Replicate values as people type them: the one rule for a list of numbers given as text.

Why a rule of its own: "1397,8" typed into a list field was stored as two replicates, 1397 and 8, with
no word; a comma is a decimal separator in much of Europe and a list or thousands separator elsewhere.
The rule, which the CLI (``demcal material add-measurement --values``) applies here and the web page
applies in its own script (the page has no Python), is:

* values are separated by semicolons, whitespace or newlines, or by a comma followed by whitespace
  ("1412, 1383", as lists are written in English);
* a number takes a decimal point, or instead a single decimal comma where that reading is the only
  one: "1397,8" is 1397.8, "0,397" is 0.397 and "1397,800" is 1397.8 (grouping would have split four
  digits), but "1,397" (1.397, or 1397 with a thousands separator?) is refused, as is any number with
  two commas or both a comma and a point, and any decimal comma in a list that also separates values
  with ", " ("12,5, 24": 12.5 and 24, or 12, 5 and 24?);
* anything else (an empty list, a word, nan or inf) is refused; every refusal names the field.

tests/service/data/number_lists.json holds the cases both implementations are tested on.

The API takes JSON numbers, which need none of this.
"""
from __future__ import annotations

import math
import re

SEPARATORS = re.compile(r"[;\s]+|,(?=\s)")
_COMMA_SEPARATES = re.compile(r",(\s|$)")
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
    text = text.strip()
    tokens = [t.rstrip(",") for t in SEPARATORS.split(text) if t.rstrip(",")]
    if not tokens:
        raise ReplicateError(f"{field}: no values (separate replicates with ';', spaces or new lines)")
    if _COMMA_SEPARATES.search(text):
        mixed = next((t for t in tokens if "," in t), None)
        if mixed is not None:
            raise ReplicateError(f"{field}: {mixed!r}: the list also separates values with ', ', so this comma "
                                 "could be either; separate values with ; or spaces, or write a decimal point")
    return [parse_number(token, field) for token in tokens]


__all__ = ["ReplicateError", "parse_number", "parse_replicates"]
