"""The cost check at campaign creation sees the jobs the runner will queue.

A material's DST measurements decide the normal stresses the battery shears at
(``calibration.conditions.battery_options``), so a material measured at more loads than the default
four costs more simulated time per battery. Creation used to check specs without those loads and let
such a campaign through, to fail at queueing; now every run's spec is built once
(``calibration.conditions.run_spec``) and checked as it will be queued. The limit is set between the
cost of the battery's default four loads (the thesis's) and that of eight, so only the loads derived
from the measurements can cross it. The bundled aggregate's DST measurements carry no normal stress, so
a copy of it shears at the default four until residual shear stresses at eight loads are added.
"""
import math

from conftest_s2 import API, campaign_body, editable_thesis_copy, running_app, s2_settings

from calibration.conditions import run_spec
from calibration.keys import ResponseKey
from engine.lab.cost import estimate
from service.campaigns.schemas import CampaignCreate

THESIS_LOADS_PA = (10.5e3, 24.0e3, 38.3e3, 52.4e3)      # thesis Table 4.5's normal stresses
EXTRA_LOADS_PA = (15.0e3, 30.0e3, 45.0e3, 60.0e3)


def _seconds(body: dict, loads) -> float:
    config = CampaignCreate.model_validate(body)
    keys = [ResponseKey.of("dst", "residual_shear_stress_pa", {"normal_stress_pa": s}) for s in loads]
    natural = {f.name: f.high for f in config.factors}
    return estimate(run_spec(config, natural, 0, keys)).simulated_time_s


def test_a_material_measured_at_more_loads_is_refused_at_creation_not_at_queueing(tmp_path):
    body = campaign_body(1, evaluator="dem", fidelity="screening", targets=None)
    four, eight = _seconds(body, THESIS_LOADS_PA), _seconds(body, THESIS_LOADS_PA + EXTRA_LOADS_PA)
    assert eight > four  # more loads, more shearing
    settings = s2_settings(tmp_path).model_copy(update={"max_simulated_time_s": 0.5 * (four + eight)})
    with running_app(settings) as (client, _):
        material_id = editable_thesis_copy(client)
        ok = client.post(f"{API}/campaigns", json={**body, "material_id": material_id})
        assert ok.status_code == 201, ok.text  # the default four loads fit
        for stress in THESIS_LOADS_PA + EXTRA_LOADS_PA:  # a Mohr-Coulomb residual strength, 32 deg
            added = client.post(f"{API}/materials/{material_id}/measurements", json={
                "test": "dst", "quantity": "residual_shear_stress_pa", "condition": {"normal_stress_pa": stress},
                "values": [math.tan(math.radians(32.0)) * stress]})
            assert added.status_code == 201, added.text
        refused = client.post(f"{API}/campaigns", json={**body, "material_id": material_id})
        assert refused.status_code == 422, refused.text
        detail = refused.json()["detail"][0]
        assert "measurements" in detail["msg"] and detail["loc"][-1] == "dst_normal_stresses_pa", detail
