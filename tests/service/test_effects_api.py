"""The effect catalogue names exactly the engine's registry and the diagnosis's candidates."""
from conftest_s2 import API, s2  # noqa: F401

from engine.candidates import candidates
from engine.effects import REGISTRY


def test_catalogue_lists_every_registered_effect_with_its_parameters_and_candidate(s2):
    client, app, settings = s2
    body = client.get(f"{API}/effects").json()
    names = [e["name"] for e in body["effects"]]
    assert names == list(REGISTRY)
    rolling = next(e for e in body["effects"] if e["name"] == "rolling_epsd2")
    assert rolling["parameters"][0]["name"] == "rolling_friction" and rolling["parameters"][0]["minimum"] == 0
    assert rolling["candidate"]["factor"] == "effects.rolling_epsd2.rolling_friction"
    assert rolling["candidate"]["fingerprint"]["friction_angle"] == "+"
    hertz = next(e for e in body["effects"] if e["name"] == "hertz_mindlin")
    assert hertz["candidate"]["switch"] is True
    listed = {e["candidate"]["name"] for e in body["effects"] if e["candidate"]} | {
        c["name"] for c in body["other_candidates"]}
    assert listed == set(candidates())
