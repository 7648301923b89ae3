"""Revision 0003_rigs: a database at 0002 with the bundled material upgrades; the start-up seed then gives
the bundled material its rig and particles, and a user's material keeps none (it named none)."""
from __future__ import annotations

import sqlalchemy as sa
from alembic import command

from conftest_s2 import API, THESIS_MATERIAL, running_app, s2_settings
from service.db import make_engine
from service.migrate import alembic_config, upgrade


def test_0003_upgrades_a_populated_0002_database(tmp_path):
    settings = s2_settings(tmp_path)
    url = settings.database_url
    assert upgrade(url, "0002_campaigns") == "0002_campaigns"
    engine = make_engine(url)
    with engine.begin() as conn:
        for name, bundled in ((THESIS_MATERIAL, 1), ("old gravel", 0)):
            conn.execute(sa.text(
                "INSERT INTO materials (name, description, source, bundled, direct_estimates, created_at, updated_at) "
                "VALUES (:n, '', '', :b, '{}', '2026-11-22 00:00:00', '2026-11-22 00:00:00')"), {"n": name, "b": bundled})
    engine.dispose()
    with running_app(settings) as (client, _):  # upgrades to head, seeds the bundled rigs and material
        materials = {m["name"]: m for m in client.get(f"{API}/materials").json()["items"]}
        assert materials[THESIS_MATERIAL]["rig"] == "thesis-590mm-shear-box"
        assert materials[THESIS_MATERIAL]["particles"]["solid_density_kg_m3"] == 2586.5
        assert materials["old gravel"]["rig"] is None and materials["old gravel"]["particles"] is None
    engine = make_engine(url)
    with engine.begin() as conn:
        command.downgrade(alembic_config(url, conn), "0002_campaigns")
    assert "rigs" not in set(sa.inspect(engine).get_table_names())
    assert "rig_id" not in {c["name"] for c in sa.inspect(engine).get_columns("materials")}
    engine.dispose()
