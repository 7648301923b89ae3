"""The data-dependent alias rule: the leading candidate is named alone only when the residuals prefer it
significantly over a rival (calibration.attribute.separation_z). Cases from the geometry of two unit
signatures with a known cosine; the z values are worked by hand in each test."""
import math

import numpy as np

from calibration import stats
from calibration.attribute import SEPARATION_Z, Ranked, _alias_groups, separation_z


def _two_signatures(cos: float):
    u_a = np.array([1.0, 0.0, 0.0])
    u_b = np.array([cos, math.sqrt(1.0 - cos * cos), 0.0])
    return u_a, u_b


def _ranked(r, vectors):
    M = np.eye(len(r))
    rows = [Ranked(name, name, stats.score_test(r, v, M), 1.0, 1.0, None, True, projected=M @ v)
            for name, v in vectors]
    rows.sort(key=lambda x: -x.score.lm)
    return rows


def test_separation_z_by_hand():
    # LM 25 against 16 at cos 0.8: (5 - 4) / sqrt(2 * 0.2) = 1.581
    assert math.isclose(separation_z(25.0, 16.0, 0.8), 1.0 / math.sqrt(0.4))
    # LM 100 against 64 at cos 0.8: (10 - 8) / sqrt(0.4) = 3.162
    assert math.isclose(separation_z(100.0, 64.0, 0.8), 2.0 / math.sqrt(0.4))


def test_rival_not_told_apart_joins_the_leads_group():
    # residual 5 u_b: the truth is b; a scores (5 * 0.8)^2 = 16 against b's 25, z = 1.58 < 1.645
    u_a, u_b = _two_signatures(0.8)
    ranked = _ranked(5.0 * u_b, [("a", u_a), ("b", u_b)])
    assert [x.name for x in ranked] == ["b", "a"]
    groups = _alias_groups(ranked, ["x", "y", "z"])
    assert len(groups) == 1 and set(groups[0]["effects"]) == {"a", "b"}
    z = groups[0]["separators"][0]["separation_z"]
    assert math.isclose(z, 1.0 / math.sqrt(0.4)) and z < SEPARATION_Z


def test_strong_evidence_separates_the_same_pair():
    # twice the strength: z = 3.16, the data prefer b whichever is true, and no group forms (cos 0.8 < 0.9)
    u_a, u_b = _two_signatures(0.8)
    ranked = _ranked(10.0 * u_b, [("a", u_a), ("b", u_b)])
    assert _alias_groups(ranked, ["x", "y", "z"]) == []
    assert ranked[0].alias_group is None


def test_a_rival_acting_the_wrong_way_never_joins():
    # b pushes the residual the other way (gamma < 0 for -u_b): no claim that it explains anything
    u_a, u_b = _two_signatures(0.8)
    ranked = _ranked(5.0 * u_a, [("a", u_a), ("b", -u_b)])
    assert _alias_groups(ranked, ["x", "y", "z"]) == []
