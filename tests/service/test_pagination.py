"""Issue 32, item 1: every listing is paginated, with a bounded limit, an offset, a stable order and a
total. ``GET /materials`` answered every material at once (7 MB per full-size one), as did campaigns,
schedules and a schedule's firings, which grow by one per due time for ever."""
from __future__ import annotations

from datetime import datetime, timedelta

import pytest
from conftest_s2 import API, campaign_body, s2, thesis_material_id  # noqa: F401
from test_campaign_cli import run, server  # noqa: F401  (the live-server fixture)

from service.api.params import CampaignLimit, FiringLimit, IterationLimit, JobLimit, MaterialLimit, ScheduleLimit


def walk(client, path: str, limit: int, **params) -> list[dict]:
    """Every item of a listing, page by page, checking each page's envelope on the way."""
    items, offset = [], 0
    while True:
        r = client.get(f"{API}{path}", params={**params, "limit": limit, "offset": offset})
        assert r.status_code == 200, r.text
        page = r.json()
        assert (page["limit"], page["offset"]) == (limit, offset)
        assert len(page["items"]) == min(limit, max(0, page["total"] - offset))
        items += page["items"]
        offset += limit
        if offset >= page["total"]:
            return items


def limit_bound(annotated) -> int:
    """The ``le`` of a ``page_limit`` (the query parameter's own bound, not a copy of the number)."""
    (query,) = annotated.__metadata__
    return next(m.le for m in query.metadata if hasattr(m, "le"))


@pytest.mark.parametrize("path, annotated", [("/jobs", JobLimit), ("/materials", MaterialLimit),
                                             ("/campaigns", CampaignLimit), ("/schedules", ScheduleLimit)])
def test_limit_is_bounded(client, path, annotated):
    bound = limit_bound(annotated)
    for bad in (0, bound + 1):
        r = client.get(f"{API}{path}", params={"limit": bad})
        assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["query", "limit"], r.text
    r = client.get(f"{API}{path}", params={"limit": bound, "offset": 0})
    assert r.status_code == 200 and r.json()["total"] == 0 and r.json()["items"] == []
    assert client.get(f"{API}{path}", params={"offset": -1}).status_code == 422


def test_materials_page_by_id_with_the_total(client):
    ids = [client.post(f"{API}/materials", json={"name": f"m{i}"}).json()["id"] for i in range(7)]
    first = client.get(f"{API}/materials").json()  # the default page holds all seven
    assert first["total"] == 7 and first["offset"] == 0 and [m["id"] for m in first["items"]] == sorted(ids)
    seen = [m["id"] for m in walk(client, "/materials", 3)]
    assert seen == sorted(ids)  # every row once, in id order, over pages of 3, 3 and 1
    past = client.get(f"{API}/materials", params={"offset": 7}).json()
    assert past["items"] == [] and past["total"] == 7


def test_a_material_s_measurements_page_by_id(client):
    from service.materials.store import BUNDLED_FILES, load_bundled

    fills = [m for m in load_bundled(BUNDLED_FILES[0]).measurements if m.test == "fill"]  # five quantities
    body = {"name": "fills", "measurements": [m.model_dump(exclude_none=True) for m in fills]}
    material = client.post(f"{API}/materials", json=body).json()
    rows = walk(client, f"/materials/{material['id']}/measurements", 2)
    assert [r["quantity"] for r in rows] == [m.quantity for m in fills] and len(rows) == 5
    assert [r["id"] for r in rows] == sorted(r["id"] for r in material["measurements"])
    assert client.get(f"{API}/materials/999/measurements").status_code == 404


def test_campaigns_page_newest_first_and_the_total_counts_the_filter(s2):  # noqa: F811
    client, _, _ = s2
    material_id = thesis_material_id(client)
    ids = [client.post(f"{API}/campaigns", json=campaign_body(material_id, name=f"c{i}")).json()["id"] for i in range(3)]
    client.post(f"{API}/campaigns/{ids[0]}/start")
    seen = [c["id"] for c in walk(client, "/campaigns", 2)]
    assert seen == sorted(ids, reverse=True)
    drafts = client.get(f"{API}/campaigns", params={"status": "draft", "limit": 1}).json()
    assert drafts["total"] == 2 and [c["id"] for c in drafts["items"]] == [ids[2]]


def test_schedules_and_firings_page_by_id(s2):  # noqa: F811
    from service.models.schedule import ScheduleFiring

    client, app, _ = s2
    template = campaign_body(thesis_material_id(client))
    ids = [client.post(f"{API}/schedules", json={"name": f"s{i}", "cron": "0 2 * * *", "template": template}).json()["id"]
           for i in range(3)]
    assert [s["id"] for s in walk(client, "/schedules", 2)] == ids
    due = datetime(2026, 1, 1, 2, 0)
    with app.state.session_factory() as session:  # five years of a daily schedule would be 1,826 rows
        session.add_all([ScheduleFiring(schedule_id=ids[1], due_at=due + timedelta(days=d), fired_at=due + timedelta(days=d),
                                        missed_count=0, skipped_reason="test") for d in range(5)])
        session.commit()
    firings = walk(client, f"/schedules/{ids[1]}/firings", 2)
    assert [f["due_at"] for f in firings] == [(due + timedelta(days=d)).isoformat() + "Z" for d in range(5)]
    assert client.get(f"{API}/schedules/{ids[0]}/firings").json()["total"] == 0
    assert client.get(f"{API}/schedules/999/firings").status_code == 404
    bound = limit_bound(FiringLimit)
    assert client.get(f"{API}/schedules/{ids[1]}/firings", params={"limit": bound + 1}).status_code == 422


def test_a_campaign_s_iterations_page_by_number(s2):  # noqa: F811
    """Iterations grow without bound through manual additions and each carries its design, runs and
    report: the listing pages them in the order they ran, whatever order the rows were written in."""
    from service.models.campaign import CampaignIteration

    client, app, _ = s2
    cid = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client))).json()["id"]
    with app.state.session_factory() as session:
        session.add_all([CampaignIteration(campaign_id=cid, number=n, parameters={}) for n in (3, 1, 2)])
        session.commit()
    assert [it["number"] for it in walk(client, f"/campaigns/{cid}/iterations", 2)] == [1, 2, 3]
    last = client.get(f"{API}/campaigns/{cid}/iterations", params={"limit": 1, "offset": 2}).json()
    assert last["total"] == 3 and [it["number"] for it in last["items"]] == [3]
    assert client.get(f"{API}/campaigns/999/iterations").status_code == 404
    bound = limit_bound(IterationLimit)
    assert client.get(f"{API}/campaigns/{cid}/iterations", params={"limit": bound + 1}).status_code == 422

def test_jobs_order_is_stable_across_pages(client):
    """Newest first by id: paging while nothing changes shows each job once."""
    ids = [client.post(f"{API}/jobs", json={"evaluator": "analytic", "seed": i}).json()["id"] for i in range(5)]
    assert [j["id"] for j in walk(client, "/jobs", 2)] == sorted(ids, reverse=True)


def test_cli_lists_say_how_many_of_the_total_and_where_the_next_page_starts(server, capsys):  # noqa: F811
    url, _, _ = server
    for i in range(2):
        assert run(capsys, "material", "create", "--url", url, "--name", f"extra {i}")[0] == 0
    code, out, err = run(capsys, "material", "list", "--url", url, "--limit", "2")
    assert code == 0, err
    assert out.rstrip().endswith("1-2 of 3 (next page: --offset 2)")  # the bundled material and the two new ones
    code, out, _ = run(capsys, "material", "list", "--url", url, "--limit", "2", "--offset", "2")
    assert "extra 1" in out and out.rstrip().endswith("3-3 of 3")
    code, out, _ = run(capsys, "material", "list", "--url", url)
    assert out.rstrip().endswith("3 in all")
    code, _, err = run(capsys, "material", "list", "--url", url, "--limit", "100000")
    assert code == 2 and "HTTP 422" in err and "limit" in err
