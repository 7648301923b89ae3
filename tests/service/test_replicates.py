"""The one rule for replicate lists typed as text (service.materials.replicates)."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from service.materials.replicates import ReplicateError, parse_replicates


@pytest.mark.parametrize("text,values", [
    ("1412; 1383.6; 1397.8", [1412.0, 1383.6, 1397.8]),
    ("1412 1383.6\n1397.8", [1412.0, 1383.6, 1397.8]),
    (" 1412;;\t1383.6 ;\n", [1412.0, 1383.6]),
    ("1397,8", [1397.8]),                # the page's bug: one value with a decimal comma, not 1397 and 8
    ("1412; 1383,6; 1397,8", [1412.0, 1383.6, 1397.8]),
    ("0,397", [0.397]),                  # a thousands separator never follows a lone zero
    ("1397,800", [1397.8]),              # four digits before the comma: grouping would have split them
    ("-2,5 +3,25", [-2.5, 3.25]),
    ("1,5e3 2.5E-1", [1500.0, 0.25]),  # exponents are not grouped
    (",5 7.", [0.5, 7.0]),
])
def test_unambiguous_lists_are_read(text, values):
    assert parse_replicates(text) == pytest.approx(values)


@pytest.mark.parametrize("text,needle", [
    ("1,397", "ambiguous"),              # 1.397 or 1397?
    ("12,500; 13", "ambiguous"),
    ("-999,000", "ambiguous"),
    ("1,397,800", "thousands separator"),
    ("1.397,8", "mixes"),
    ("1,397.8", "mixes"),
    ("17,18,19", "thousands separator"),  # a comma-separated list is not a list here
    ("a; b", "not a number"),
    ("nan", "not a number"),
    ("1e999", "not a finite number"),
    ("  ;\n ", "no values"),
])
def test_ambiguous_or_unreadable_lists_are_refused_naming_the_field(text, needle):
    with pytest.raises(ReplicateError) as caught:
        parse_replicates(text, "--values")
    message = str(caught.value)
    assert message.startswith("--values: ") and needle in message and "\n" not in message


CASES = json.loads((Path(__file__).parent / "data" / "number_lists.json").read_text())


@pytest.mark.parametrize("text,values", CASES["read"])
def test_the_shared_cases_read_as_the_page_reads_them(text, values):
    # the page's numbers.js runs on the same file (tests/service/test_browser.py)
    assert parse_replicates(text) == pytest.approx(values)


@pytest.mark.parametrize("text", CASES["refused"])
def test_the_shared_cases_refused_as_the_page_refuses_them(text):
    with pytest.raises(ReplicateError):
        parse_replicates(text, "--values")
