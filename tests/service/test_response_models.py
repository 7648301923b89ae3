"""Every route says what it answers, the OpenAPI shows what the page reads, and typing changed nothing.

The last test is the guard for the builders: the report, diagnosis and history are dicts built and
stored by the campaign code; their response models must let every key through unchanged, so a key
added to a builder and not to its model fails here instead of vanishing from the API.
"""
from __future__ import annotations

import json
import types
import typing

import pytest
from fastapi.encoders import jsonable_encoder
from fastapi.routing import APIRoute, iter_route_contexts
from pydantic import BaseModel

from conftest_s2 import API, campaign_body, run_to_end, s2, thesis_material_id  # noqa: F401

# Routes that answer no JSON body to type, each with the reason.
NOT_JSON = {
    ("GET", "/"): "the web page (HTML file)",
    ("GET", "/ui"): "redirect to the web page",
    ("GET", "/favicon.ico"): "the page's icon (SVG file)",
    ("GET", f"{API}/docs"): "Swagger UI (HTML)",
    ("GET", f"{API}/redoc"): "ReDoc (HTML)",
    ("DELETE", f"{API}/materials/{{material_id}}"): "204 No Content",
    ("DELETE", f"{API}/materials/{{material_id}}/measurements/{{measurement_id}}"): "204 No Content",
    ("DELETE", f"{API}/schedules/{{schedule_id}}"): "204 No Content",
}


def _typed(tp) -> bool:
    """A response type names its contents: a model, a scalar, or containers and unions of those
    (not ``dict``, ``list`` or ``Any``)."""
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return True
    if tp in (int, float, str, bool, type(None)):
        return True
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin in (list, dict, typing.Union, types.UnionType) and args:
        return all(_typed(a) for a in args)
    return False


def _api_routes(app):
    for context in iter_route_contexts(app.routes):
        if isinstance(context.original_route, APIRoute):
            for method in context.methods:
                yield method, context.path, context.original_route


def test_every_route_has_a_response_model_or_is_a_listed_non_json_route(s2):
    client, app, settings = s2
    seen, untyped = set(), []
    for method, path, route in _api_routes(app):
        seen.add((method, path))
        if (method, path) in NOT_JSON:
            continue
        if route.response_model is None or not _typed(route.response_model):
            untyped.append(f"{method} {path}: {route.response_model}")
    assert not untyped, "routes without a response model:\n" + "\n".join(untyped)
    assert set(NOT_JSON) <= seen, f"listed exceptions that are no routes: {set(NOT_JSON) - seen}"
    assert len(seen) - len(NOT_JSON) >= 40


def test_the_typing_check_refuses_open_dicts():
    assert not _typed(dict) and not _typed(list[dict]) and not _typed(dict[str, typing.Any])
    assert _typed(dict[str, list[float | None]])


def _schema(spec: dict, ref_or_schema: dict) -> dict:
    """Follow $ref, and anyOf[..., null], to the object schema."""
    while True:
        if "$ref" in ref_or_schema:
            ref_or_schema = spec["components"]["schemas"][ref_or_schema["$ref"].rsplit("/", 1)[1]]
        elif "anyOf" in ref_or_schema:
            ref_or_schema = next(s for s in ref_or_schema["anyOf"] if s.get("type") != "null")
        elif ref_or_schema.get("type") == "array":
            ref_or_schema = ref_or_schema["items"]
        elif ref_or_schema.get("type") == "object" and "additionalProperties" in ref_or_schema \
                and "properties" not in ref_or_schema:
            ref_or_schema = ref_or_schema["additionalProperties"]
        else:
            return ref_or_schema


def _answer(spec: dict, path: str) -> dict:
    body = spec["paths"][f"{API}{path}"]["get"]["responses"]["200"]["content"]["application/json"]["schema"]
    return _schema(spec, body)


def _documents(spec: dict, schema: dict, keys: set[str]) -> None:
    missing = keys - set(schema.get("properties", {}))
    assert not missing, f"{schema.get('title')}: the OpenAPI does not document {sorted(missing)}"


# the keys service/web/static/js/campaign_*.js read
REPORT = {"verdict", "meaning", "lack_of_fit", "tests", "adequacy", "conflicts", "surrogate_check", "polish",
          "targets", "confirmation_seeds", "confirmation_job_id", "reachable_limit", "diagnosis", "automatic"}
TARGET = {"test", "quantity", "condition", "unit", "status", "measured", "measured_uncertainty",
          "uncertainty_assumed", "simulator_sd", "residual_sd", "predicted", "prediction_interval", "confirmed",
          "confirmation_in_interval", "standardised_residual", "predicted_standardised_residual",
          "reachability", "reachable"}
DIAGNOSIS = {"verdict", "message", "ranking", "critical_lm", "fingerprints", "alias_groups", "measure_next",
             "indicated", "adequacy", "directed", "lack_of_fit"}
RANKED = {"effect", "title", "lm", "p_holm", "explained", "strength", "plausible_range", "unit", "alias_group",
          "significant"}
HISTORY_ENTRY = {"number", "effects", "added_effect", "optimum", "parameter_std", "parameter_interval", "chi2", "chi2_per_dof", "dof",
                 "noise_band", "lack_of_fit_p", "adequacy_p", "directed_p", "per_test", "weighted_rms", "verdict",
                 "top_effect", "decision", "stop_reason", "range_widened", "effect_added_next"}


def test_the_openapi_documents_the_report_the_diagnosis_and_the_history(s2):
    client, app, settings = s2
    spec = client.get(f"{API}/openapi.json").json()
    report = _answer(spec, "/campaigns/{campaign_id}/report")
    _documents(spec, report, REPORT | {"campaign_id", "iteration"})
    _documents(spec, _schema(spec, report["properties"]["targets"]), TARGET)
    _documents(spec, _schema(spec, report["properties"]["lack_of_fit"]),
               {"statistic", "dof", "p_value", "chi2_per_dof", "noise_band"})
    _documents(spec, _schema(spec, report["properties"]["polish"]), {"steps", "batteries", "chi2_start", "chi2", "skipped"})
    diagnosis = _answer(spec, "/campaigns/{campaign_id}/diagnosis")
    _documents(spec, diagnosis, DIAGNOSIS | {"campaign_id", "iteration"})
    _documents(spec, _schema(spec, diagnosis["properties"]["ranking"]), RANKED)
    _documents(spec, _schema(spec, diagnosis["properties"]["fingerprints"]), {"columns", "observed", "effects"})
    history = _answer(spec, "/campaigns/{campaign_id}/history")
    _documents(spec, history, {"campaign_id", "iterations", "targets"})
    _documents(spec, _schema(spec, history["properties"]["iterations"]), HISTORY_ENTRY)
    _documents(spec, _schema(spec, history["properties"]["targets"]), {"test", "quantity", "condition", "residuals"})
    iteration = _answer(spec, "/campaigns/{campaign_id}/iterations/{number}")
    _documents(spec, iteration, {"number", "phase", "parameters", "design", "report", "runs"})
    summary = _answer(spec, "/campaigns/{campaign_id}")
    _documents(spec, summary, {"status", "phase", "current_iteration", "runs_total", "runs_succeeded",
                               "runs_failed", "error", "stop_reason", "config"})
    # a described field says what it is
    assert report["properties"]["reachable_limit"].get("description")


def _same(a, b, path="") -> None:
    """Equal JSON, with the same number types (an int stays an int)."""
    assert type(a) is type(b), f"{path}: {a!r} became {b!r}"
    if isinstance(a, dict):
        assert a.keys() == b.keys(), f"{path}: keys {sorted(a.keys() ^ b.keys())} differ"
        for k in a:
            _same(a[k], b[k], f"{path}/{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _same(x, y, f"{path}[{i}]")
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


def _untyped(value):
    return json.loads(json.dumps(jsonable_encoder(value)))


def test_typed_answers_equal_what_the_builders_return(s2):
    """An automatic campaign (reports, a diagnosis, decisions, a widened range, polishing): each route's
    answer equals its endpoint's own dict, key for key."""
    from service.api import campaigns as routes, jobs as job_routes

    client, app, settings = s2
    cid = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client), automatic=True)).json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    assert run_to_end(client, app, settings, cid, max_rounds=60)["status"] == "completed"
    numbers = [it["number"] for it in client.get(f"{API}/campaigns/{cid}/iterations").json()["items"]]
    assert len(numbers) >= 2
    checked = []
    with app.state.session_factory() as session:
        def check(url: str, raw) -> None:
            response = client.get(f"{API}{url}")
            assert response.status_code == 200, (url, response.text)
            _same(_untyped(raw), response.json(), url)
            checked.append(url)

        check(f"/campaigns/{cid}", routes.status(campaign_id=cid, session=session))
        check("/campaigns", routes.list_all(session=session, status=None, limit=100, offset=0))
        check(f"/campaigns/{cid}/iterations", routes.iterations(campaign_id=cid, session=session))
        check(f"/campaigns/{cid}/history", routes.history(campaign_id=cid, session=session))
        for n in numbers:
            q = f"?number={n}"
            check(f"/campaigns/{cid}/iterations/{n}", routes.one_iteration(campaign_id=cid, number=n, session=session))
            for name in ("design", "models", "optimum", "confirmation", "report"):
                check(f"/campaigns/{cid}/{name}{q}", getattr(routes, name)(session=session, campaign_id=cid, number=n))
            report = client.get(f"{API}/campaigns/{cid}/report{q}").json()
            if "diagnosis" in report:
                check(f"/campaigns/{cid}/diagnosis{q}", routes.diagnosis(session=session, campaign_id=cid, number=n))
        job_id = client.get(f"{API}/campaigns/{cid}/report").json()["confirmation_job_id"]
        check(f"/jobs/{job_id}/result", job_routes.get_result(session=session, job_id=job_id))
        check(f"/jobs/{job_id}/result?include_curves=false",
              job_routes.get_result(session=session, job_id=job_id, include_curves=False))
        check(f"/jobs/{job_id}/curves", job_routes.get_curves(job_id=job_id, session=session))
        for curve in client.get(f"{API}/jobs/{job_id}/curves").json():
            check(f"/jobs/{job_id}/curves/{curve}", job_routes.get_curve(session=session, job_id=job_id, name=curve))
    assert any("/diagnosis" in url for url in checked)
    reports = [client.get(f"{API}/campaigns/{cid}/report?number={n}").json() for n in numbers]
    assert any((r.get("automatic") or {}).get("decision") for r in reports)


def test_catalogues_answer_what_their_builders_return(s2):
    from service.api import effects, materials

    client, app, settings = s2
    _same(_untyped(effects.list_effects()), client.get(f"{API}/effects").json(), "/effects")
    _same(_untyped(materials.quantities()), client.get(f"{API}/materials/quantities").json(), "/quantities")


@pytest.mark.parametrize("path", ["/health"])
def test_health_keeps_its_keys(s2, path):
    client, app, settings = s2
    body = client.get(f"{API}{path}").json()
    assert {"status", "version", "executor", "local_workers_alive", "local_worker_pids", "database",
            "schema_revision", "jobs"} <= body.keys() and "dask" not in body


def test_an_alias_refit_s_records_survive_the_report_s_model():
    """The automatic record of a loop that fitted an alias in place of a kept effect (the test bed's elongation 1.8,
    seed 8: tests/calibration/test_verdict_rules.py) keeps every key through ``Automatic``."""
    from calibration.conditions import standin_conditions
    from calibration.evaluators import StandinEvaluator
    from calibration.loop import CalibrationLoop
    from calibration.testbed import OPTIONS, loop_settings, make_case
    from service.api.responses.report import Automatic

    case = make_case(8, "single", effects={"particle_shape": 1.8})
    result = CalibrationLoop(case.targets, StandinEvaluator(standin_conditions(OPTIONS)), loop_settings(case)).run()
    leader, partner = (it.report["automatic"] for it in result.iterations[1:3])
    assert "alias_refit" in leader and "alias_settled" in partner
    for record in (leader, partner):
        typed = Automatic.model_validate(record).model_dump(exclude_none=True)
        assert {k for k, v in record.items() if v is not None} - {"next_config"} <= set(typed), sorted(record)
    assert Automatic.model_validate(partner).alias_settled.kept_iteration == result.final.number
