"""Issue 33's verdict rules through the service, on the bundled thesis aggregate with the analytic
evaluator (a few seconds each): a measurement typed in the wrong unit is named, with its factor, and the
automatic mode stops there; an effect is added against "no physical match" only with an explicit override.

The unit slip is the one a user makes with the thesis's own number: the confined modulus, 8.69 MPa
(Section 4.5.5), typed as 8.69 with the unit kPa, i.e. 1,000 times too small.
"""
from __future__ import annotations

from conftest_s2 import API, campaign_body, editable_thesis_copy, run_to_end, s2  # noqa: F401

THESIS_MODULUS_MPA = 8.69  # Section 4.5.5 / Table 4.10: average of 3 CCTs


def _replace_measurement(client, material_id: int, test: str, quantity: str, **new) -> None:
    material = client.get(f"{API}/materials/{material_id}").json()
    old = next(m for m in material["measurements"] if m["test"] == test and m["quantity"] == quantity)
    assert client.delete(f"{API}/materials/{material_id}/measurements/{old['id']}").status_code == 204
    added = client.post(f"{API}/materials/{material_id}/measurements",
                        json={"test": test, "quantity": quantity, "condition": old["condition"], **new})
    assert added.status_code == 201, added.text


def test_a_modulus_typed_1000_times_too_small_is_named_and_the_automatic_mode_stops(s2):
    client, app, settings = s2
    material_id = editable_thesis_copy(client)
    _replace_measurement(client, material_id, "cct", "confined_modulus_pa", values=[THESIS_MODULUS_MPA],
                         unit="kPa", reported_replicates=3)
    body = campaign_body(material_id, automatic=True, max_iterations=3)
    cid = client.post(f"{API}/campaigns", json=body).json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    summary = run_to_end(client, app, settings, cid, max_rounds=60)
    assert summary["status"] == "completed", summary
    # stopped at the first iteration, naming the measurement and the slip, with no effect added
    assert summary["stop_reason"].startswith("suspect measurement: cct confined_modulus_pa"), summary["stop_reason"]
    assert "1,000 times too small: typed in kPa, meant in MPa?" in summary["stop_reason"]
    history = client.get(f"{API}/campaigns/{cid}/history").json()["iterations"]
    assert len(history) == 1 and history[0]["effect_added_next"] is None
    report = client.get(f"{API}/campaigns/{cid}/report").json()
    assert report["verdict"] == "suspect measurement"
    suspect, = report["suspect_measurements"]
    assert (suspect["test"], suspect["quantity"], suspect["factor"], suspect["meant_unit"]) == \
        ("cct", "confined_modulus_pa", 1000.0, "MPa")
    assert suspect["measured"] == [THESIS_MODULUS_MPA * 1e3]  # stored in SI: 8.69 kPa = 8,690 Pa
    assert next(c for c in report["checks"] if c["check"].startswith("measurements plausible"))["holds"] is False


# The thesis aggregate's bulk density (Table 4.5, runs 1-3) 1.5 times over: a packing far denser than any
# sphere assembly of these particles reaches, which only an implausible Hertz modulus "explains"
IMPOSSIBLE_BULK_DENSITY = [1.5 * v for v in (1412.0, 1383.6, 1397.8)]
# the particle density measured directly (thesis Section 4.5.2, water displacement, 2,586.5 kg/m3; 1 % for a
# pycnometer's repeatability): no particle density reaches that bulk density without contradicting it, so a wider
# box is not the answer (calibration.decisions.widened_box) and the misfit matches no physics
DENSITY_PRIOR = {"parameter": "particle_density_kg_m3", "value": 2586.5, "uncertainty": 25.865}


def no_physical_match_campaign(client, app, settings) -> int:
    """A completed campaign whose diagnosis is "no physical match" while one effect is significant."""
    material_id = editable_thesis_copy(client, "impossible density")
    _replace_measurement(client, material_id, "fill", "bulk_density_kg_m3", values=IMPOSSIBLE_BULK_DENSITY,
                         unit="kg/m3")
    cid = client.post(f"{API}/campaigns", json=campaign_body(material_id, priors=[DENSITY_PRIOR])).json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    assert run_to_end(client, app, settings, cid)["status"] == "completed"
    return cid


def test_no_physical_match_adds_an_effect_only_on_an_explicit_override(s2):
    client, app, settings = s2
    cid = no_physical_match_campaign(client, app, settings)
    diagnosis = client.get(f"{API}/campaigns/{cid}/diagnosis").json()
    assert diagnosis["verdict"] == "no physical match" and diagnosis["indicated"] == []
    significant = next(r["effect"] for r in diagnosis["ranking"] if r["significant"])  # what the page once offered
    refused = client.post(f"{API}/campaigns/{cid}/iterations", json={"add_effect": significant})
    assert refused.status_code == 409 and "override" in refused.text and "no physical match" in refused.text
    assert client.get(f"{API}/campaigns/{cid}").json()["status"] == "completed"  # nothing changed
    alone = client.post(f"{API}/campaigns/{cid}/iterations", json={"override": True})
    assert alone.status_code == 422 and "override needs add_effect" in alone.text
    forced = client.post(f"{API}/campaigns/{cid}/iterations", json={"add_effect": significant, "override": True})
    assert forced.status_code == 201, forced.text


def test_the_page_withholds_effects_under_the_same_verdicts_as_the_loop():
    """The page spells calibration.vocabulary.AGAINST_ADDING once, in campaign_diagnosis.js; they must agree."""
    import re
    from pathlib import Path

    from calibration.vocabulary import AGAINST_ADDING

    js = (Path(__file__).resolve().parents[2] / "service" / "web" / "static" / "js" / "campaign_diagnosis.js").read_text()
    spelt = re.search(r"const AGAINST_ADDING = new Set\(\[(.*?)\]\)", js).group(1)
    assert set(re.findall(r'"([^"]+)"', spelt)) == {v.value for v in AGAINST_ADDING}
