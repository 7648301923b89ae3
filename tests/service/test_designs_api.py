"""Design preview: the thesis's 2^(4-1) design (Table A.8) with its aliases, and error paths."""
from __future__ import annotations

from conftest_s2 import API, error_loc, s2  # noqa: F401

# The thesis's screening factors and levels (Appendix A, Table A.6), in Table A.8's order A-D.
FACTORS = [
    {"name": "rho_p", "low": 2000.0, "high": 20000.0, "unit": "kg/m3"},
    {"name": "mu_pp", "low": 0.05, "high": 0.5},
    {"name": "mu_pw", "low": 0.01, "high": 0.045},
    {"name": "k_p", "low": 1.0e6, "high": 2.0e6, "unit": "N/m"},
]
# Table A.8 runs as A B C D signs ('1001' = A high, D high), generator D = ABC.
TABLE_A8 = {"0000", "1001", "0101", "1100", "0011", "1010", "0110", "1111"}


def test_half_fraction_with_centre_runs(s2):
    client, _, _ = s2
    response = client.post(f"{API}/designs/preview", json={
        "factors": FACTORS, "type": "fractional", "generators": ["D=ABC"], "centre_runs": 3, "seed": 4})
    assert response.status_code == 200, response.text
    design = response.json()
    assert design["n_runs"] == 11 and design["resolution"] == 4
    chains = {c["label"] for c in design["aliases"]["chains"]}
    assert {"AB = CD", "AC = BD", "BC = AD"} <= chains
    factorial = [r for r in design["runs"] if r["point_type"] == "factorial"]
    centre = [r for r in design["runs"] if r["point_type"] == "center"]
    assert len(factorial) == 8 and len(centre) == 3
    for run in factorial:  # D = ABC on every factorial run, and coded <-> natural agree
        c = run["coded"]
        assert c["k_p"] == c["rho_p"] * c["mu_pp"] * c["mu_pw"]
        for f in FACTORS:
            expected = f["low"] if c[f["name"]] == -1 else f["high"]
            assert run["natural"][f["name"]] == expected
    labels = {"".join("1" if r["coded"][f["name"]] > 0 else "0" for f in FACTORS) for r in factorial}
    assert labels == TABLE_A8
    assert all(r["natural"]["rho_p"] == 11000.0 for r in centre)
    seeds = [r["seed"] for r in design["runs"]]
    assert len(set(seeds)) == len(seeds)  # centre replicates differ by seed
    assert sorted(r["run_order"] for r in design["runs"]) == list(range(1, 12))


def test_full_factorial_has_no_aliases(s2):
    client, _, _ = s2
    design = client.post(f"{API}/designs/preview", json={"factors": FACTORS[:2], "centre_runs": 0}).json()
    assert design["n_runs"] == 4
    assert all(not c["aliases"] for c in design["aliases"]["chains"])


def test_preview_errors_name_the_field(s2):
    client, _, _ = s2
    bad_generator = client.post(f"{API}/designs/preview", json={
        "factors": FACTORS, "type": "fractional", "generators": ["D=AXC"]})
    assert bad_generator.status_code == 422 and error_loc(bad_generator) == ["body", "generators"]
    missing = client.post(f"{API}/designs/preview", json={"factors": FACTORS, "type": "fractional"})
    assert missing.status_code == 422
    levels = client.post(f"{API}/designs/preview", json={"factors": [{"name": "a", "low": 2, "high": 1}]})
    assert levels.status_code == 422 and error_loc(levels)[:3] == ["body", "factors", 0]
    assert client.post(f"{API}/designs/preview", json={"factors": []}).status_code == 422
    negative = client.post(f"{API}/designs/preview", json={"factors": FACTORS[:2], "centre_runs": -1})
    assert negative.status_code == 422 and error_loc(negative) == ["body", "centre_runs"]
