"""``demcal material|campaign|schedule`` against a real HTTP server (uvicorn on a loopback port)."""
from __future__ import annotations

import json
import socket
import threading
import time

import pytest
import uvicorn

from conftest_s2 import drain, s2_settings
from service.app import create_app
from service.campaigns.runner import CampaignRunner
from service.cli import main


@pytest.fixture
def server(tmp_path):
    settings = s2_settings(tmp_path)
    app = create_app(settings)
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    config = uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning", lifespan="on")
    srv = uvicorn.Server(config)
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 30
    while not srv.started:
        assert time.monotonic() < deadline, "server did not start"
        time.sleep(0.05)
    yield f"http://127.0.0.1:{port}", app, settings
    srv.should_exit = True
    thread.join(10)


def run(capsys, *argv) -> tuple[int, str, str]:
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_material_commands(server, capsys):
    url, _, _ = server
    code, out, _ = run(capsys, "material", "list", "--url", url)
    assert code == 0 and "thesis-coarse-aggregate" in out
    code, out, _ = run(capsys, "material", "show", "1", "--url", url, "--json")
    assert code == 0 and json.loads(out)["measurements"][0]["values"] == [1412.0, 1383.6, 1397.8]
    add = ("--test", "dst", "--quantity", "residual_shear_stress_pa", "--values", "17; 18", "--unit", "kPa",
           "--condition", "normal_stress_pa=24", "--condition-unit", "normal_stress_pa=kPa")
    code, _, err = run(capsys, "material", "add-measurement", "1", "--url", url, *add)
    assert code == 2 and "HTTP 409" in err and "read-only" in err  # the bundled reference material
    code, out, _ = run(capsys, "material", "copy", "1", "--url", url, "--name", "my aggregate", "--json")
    copy = json.loads(out)
    assert code == 0 and not copy["bundled"] and len(copy["measurements"]) == 13
    code, out, _ = run(capsys, "material", "add-measurement", str(copy["id"]), "--url", url, *add)
    assert code == 0 and "2 replicate(s), mean 17500 Pa" in out  # (17 + 18) / 2 kPa
    code, _, err = run(capsys, "material", "add-measurement", str(copy["id"]), "--url", url, "--test", "dst",
                       "--quantity", "porosity", "--values", "1")
    assert code == 2 and "HTTP 422" in err and "quantity" in err
    # a confined modulus typed in kPa where Pa was meant is stored, and the CLI says which unit it likely was
    # (granular packings' confined moduli: 1 MPa to 1 GPa, docs/lab.md "Plausible ranges")
    code, out, err = run(capsys, "material", "add-measurement", str(copy["id"]), "--url", url, "--test", "cct",
                         "--quantity", "confined_modulus_pa", "--values", "8690", "--condition", "normal_stress_pa=30000",
                         "-q")
    assert code == 0 and out.strip().isdigit(), (out, err)  # -q: only the id on stdout
    assert "demcal: warning:" in err and "kPa" in err, err
    code, _, err = run(capsys, "material", "show", "99", "--url", url)
    assert code == 2 and "HTTP 404" in err
    code, _, err = run(capsys, "material", "add-measurement", str(copy["id"]), "--url", url, "--test", "dst",
                       "--quantity", "friction_angle_deg", "--values", "a b")
    assert code == 2 and "--values" in err


def test_campaign_and_schedule_commands(server, capsys, tmp_path):
    url, app, settings = server
    code, out, _ = run(capsys, "campaign", "create", "--url", url, "--name", "cli", "--material", "1",
                       "--evaluator", "analytic", "--fidelity", "thesis", "--centre-runs", "2",
                       "--factor", "particle_density_kg_m3:2300:2700", "--factor", "friction_pp:0.3:1.0",
                       "--confirmation-seeds", "3", "--polish-steps", "0", "--start", "--json")
    assert code == 0
    campaign = json.loads(out)
    cid = campaign["id"]
    assert campaign["status"] == "running"
    assert campaign["config"]["confirmation_seeds"] == 3 and campaign["config"]["polish_steps"] == 0
    code, out, _ = run(capsys, "campaign", "create", "--url", url, "--name", "cli polish", "--material", "1",
                       "--evaluator", "analytic", "--fidelity", "thesis", "--factor", "friction_pp:0.3:1.0",
                       "--polish-when", "always", "--polish-jacobian", "batteries", "--no-reuse", "--all-seeds",
                       "--no-holdout", "--json")
    config = json.loads(out)["config"]
    assert code == 0 and (config["polish_when"], config["polish_jacobian"]) == ("always", "batteries")
    assert campaign["config"]["polish_holdout"] is True and config["polish_holdout"] is False
    assert config["reuse"] is False and config["adaptive_replicates"] is False
    code, _, err = run(capsys, "campaign", "start", str(cid), "--url", url)
    assert code == 2 and "HTTP 409" in err
    assert run(capsys, "campaign", "pause", str(cid), "--url", url)[0] == 0
    code, out, _ = run(capsys, "campaign", "resume", str(cid), "--url", url)
    assert code == 0 and "running" in out
    code, _, err = run(capsys, "campaign", "report", str(cid), "--url", url)
    assert code == 2 and "HTTP 404" in err  # no iteration yet

    runner = CampaignRunner(app.state.session_factory, settings)
    for _ in range(8):
        runner.tick()
        drain(app, settings)
    code, out, _ = run(capsys, "campaign", "status", str(cid), "--url", url)
    assert code == 0 and "completed" in out
    code, out, _ = run(capsys, "campaign", "report", str(cid), "--url", url)
    assert code == 0 and "bulk_density_kg_m3" in out and "95% PI" in out
    # the thesis aggregate's 60.6 deg is out of the stand-in spheres' reach: the loop diagnoses it
    code, out, _ = run(capsys, "campaign", "diagnosis", str(cid), "--url", url)
    assert code == 0 and "rolling_epsd2" in out and "LM" in out
    code, out, _ = run(capsys, "campaign", "history", str(cid), "--url", url)
    assert code == 0 and "chi2/dof" in out
    code, _, err = run(capsys, "campaign", "next", str(cid), "--url", url, "--add-effect", "rolling_resistance")
    assert code == 2 and "HTTP 422" in err and "add_effect" in err
    code, out, _ = run(capsys, "campaign", "list", "--url", url, "--status", "completed")
    assert code == 0 and "cli" in out

    template = tmp_path / "template.json"
    template.write_text(json.dumps({"name": "nightly", "material_id": 1,
                                    "factors": [{"name": "friction_pp", "low": 0.3, "high": 1.0}]}))
    code, out, _ = run(capsys, "schedule", "create", "--url", url, "--name", "n", "--cron", "0 2 * * *",
                       "--campaign-file", str(template), "--only-new", "--json")
    assert code == 0 and json.loads(out)["only_if_new_measurements"] is True
    code, out, _ = run(capsys, "schedule", "create", "--url", url, "--name", "again", "--cron", "@daily",
                       "--from-campaign", str(cid))
    assert code == 0 and "next run" in out
    code, _, err = run(capsys, "schedule", "create", "--url", url, "--name", "x", "--cron", "99 * * * *",
                       "--from-campaign", str(cid))
    assert code == 2 and "HTTP 422" in err and "cron" in err
    code, _, err = run(capsys, "schedule", "create", "--url", url, "--name", "x", "--cron", "@daily")
    assert code == 2 and "exactly one" in err
    code, out, _ = run(capsys, "schedule", "list", "--url", url, "--json")
    ids = [s["id"] for s in json.loads(out)["items"]]
    assert len(ids) == 2
    assert run(capsys, "schedule", "delete", str(ids[0]), "--url", url)[0] == 0
    code, _, err = run(capsys, "schedule", "delete", str(ids[0]), "--url", url)
    assert code == 2 and "HTTP 404" in err
    code, _, err = run(capsys, "campaign", "create", "--url", url, "--file", str(tmp_path / "missing.json"))
    assert code == 2 and "cannot read JSON" in err


def test_unreachable_service_is_a_message_not_a_traceback(capsys):
    code, _, err = run(capsys, "campaign", "list", "--url", "http://127.0.0.1:9")
    assert code == 2 and err.startswith("demcal: cannot reach the service at http://127.0.0.1:9 (from --url)")
    assert "DEMCAL_URL" in err and err.count("\n") == 1  # how to point it elsewhere, in one line


def test_job_commands(server, capsys):
    """submit -> list -> status -> result, cancel of a queued job and its retry, errors in one line."""
    url, app, settings = server
    code, out, _ = run(capsys, "job", "submit", "--url", url, "--test", "dst", "--evaluator", "analytic",
                       "--seed", "3", "--param", "friction_pp=0.6", "--json")
    job = json.loads(out)
    assert code == 0 and job["status"] == "queued" and job["test"] == "dst"
    code, out, _ = run(capsys, "job", "submit", "--url", url, "--test", "fill", "--evaluator", "analytic", "--json")
    second = json.loads(out)
    code, out, _ = run(capsys, "job", "cancel", str(second["id"]), "--url", url)
    assert code == 0 and "cancelled" in out
    code, out, _ = run(capsys, "job", "retry", str(second["id"]), "--url", url)
    assert code == 0 and "queued" in out
    drain(app, settings)
    code, out, _ = run(capsys, "job", "list", "--url", url, "--status", "succeeded")
    assert code == 0 and str(job["id"]) in out and "dst" in out
    code, out, _ = run(capsys, "job", "status", str(job["id"]), "--url", url)
    assert code == 0 and "succeeded" in out
    code, out, _ = run(capsys, "job", "result", str(job["id"]), "--url", url)
    assert code == 0 and "friction_angle_deg" in out
    code, _, err = run(capsys, "job", "submit", "--url", url, "--param", "friction_pp=-1")
    assert code == 2 and "HTTP 422" in err and "friction_pp" in err and "Traceback" not in err
    code, _, err = run(capsys, "job", "cancel", "999999", "--url", url)
    assert code == 2 and "HTTP 404" in err


def test_material_create_and_delete(server, capsys):
    url, _, _ = server
    code, out, _ = run(capsys, "material", "create", "--url", url, "--name", "gravel 4/32",
                       "--description", "river gravel", "--json")
    material = json.loads(out)
    assert code == 0 and material["name"] == "gravel 4/32" and material["measurements"] == []
    code, _, err = run(capsys, "material", "create", "--url", url, "--name", "gravel 4/32")
    assert code == 2 and "HTTP 409" in err
    code, out, _ = run(capsys, "material", "add-measurement", str(material["id"]), "--url", url, "--test", "fill",
                       "--quantity", "bulk_density_kg_m3", "--values", "1600 1610", "--json")
    measurement = json.loads(out)
    code, out, _ = run(capsys, "material", "delete-measurement", str(material["id"]), str(measurement["id"]),
                       "--url", url)
    assert code == 0 and "deleted" in out
    code, out, _ = run(capsys, "material", "delete", str(material["id"]), "--url", url)
    assert code == 0
    code, _, err = run(capsys, "material", "delete", "1", "--url", url)
    assert code == 2 and "HTTP 409" in err  # the bundled material stays


def test_campaign_create_at_a_resolution_shows_its_cost(server, capsys):
    """Issue 29: --resolution coarse --scale-factor 2 runs the bundled material's particles at twice their
    size in its own 590 mm box, and creation prints the cost there; the factor without coarse is refused."""
    url, _, _ = server
    code, out, _ = run(capsys, "campaign", "create", "--url", url, "--name", "cli coarse", "--material", "1",
                       "--evaluator", "analytic", "--resolution", "coarse", "--scale-factor", "2",
                       "--factor", "friction_pp:0.3:1.0")
    assert code == 0, out
    assert "in rig thesis-590mm-shear-box at resolution coarse (sizes x 2)" in out and "particles" in out
    code, _, err = run(capsys, "campaign", "create", "--url", url, "--name", "cli bad", "--material", "1",
                       "--resolution", "thesis", "--scale-factor", "2", "--factor", "friction_pp:0.3:1.0")
    assert code == 2 and "apply to --resolution coarse" in err


def test_campaign_iterate_at_another_resolution(server, capsys):
    """`demcal campaign iterate ID --resolution coarse --scale-factor 1.3`: the next iteration of a campaign run in
    the 400 mm preset moves into the material's own 590 mm box (POST .../iterations {"resolution": ...})."""
    url, app, settings = server
    code, out, _ = run(capsys, "campaign", "create", "--url", url, "--name", "cli preset then coarse", "--material", "1",
                       "--evaluator", "analytic", "--fidelity", "screening", "--factor", "friction_pp:0.3:1.0",
                       "--factor", "particle_density_kg_m3:2300:2700", "--start", "-q")
    assert code == 0, out
    cid = int(out.strip())
    runner = CampaignRunner(app.state.session_factory, settings)
    for _ in range(60):
        runner.tick()
        drain(app, settings)
        code, out, _ = run(capsys, "campaign", "status", str(cid), "--url", url)
        if "completed" in out:
            break
    assert "completed" in out
    code, out, err = run(capsys, "campaign", "iterate", str(cid), "--url", url, "--resolution", "coarse",
                         "--scale-factor", "1.3", "--json")
    assert code == 0, err
    started = json.loads(out)
    assert started["fidelity"] == "coarse" and started["config"]["rig"]["name"] == "thesis-590mm-shear-box"


def test_the_history_table_names_a_widened_box(monkeypatch, capsys):
    """`demcal campaign history` says which iteration ran a wider box than the one it was built on, as the page does."""
    from types import SimpleNamespace

    from service import cli_campaigns

    entry = {"number": 1, "effects": [], "range_widened": False, "box_widened": [], "chi2_per_dof": 18.6,
             "noise_band": [0.0, 3.83], "verdict": "model misses the measurements", "effect_added_next": None}
    history = {"iterations": [entry, {**entry, "number": 2, "box_widened": ["particle_stiffness_n_per_m"]}]}
    monkeypatch.setattr(cli_campaigns, "_call", lambda *args, **kwargs: history)
    assert cli_campaigns.campaign_history(SimpleNamespace(id=1, json=False, quiet=False)) == 0
    rows = capsys.readouterr().out.splitlines()
    assert "box widened" not in rows[2] and "- (box widened: particle_stiffness_n_per_m)" in rows[3]


def test_campaign_continue(server, capsys):
    """`demcal campaign continue ID`: an automatic campaign stopped by its one-iteration limit, with an effect
    indicated (the stand-in spheres cannot reach the aggregate's 60.6 deg), goes on to add it; asked again
    beyond the ten-iteration limit, a message naming the field, not a traceback."""
    url, app, settings = server
    code, out, _ = run(capsys, "campaign", "create", "--url", url, "--name", "limit", "--material", "1",
                       "--evaluator", "analytic", "--fidelity", "thesis", "--factor", "particle_density_kg_m3:2300:2700",
                       "--factor", "particle_stiffness_n_per_m:1e6:3e6", "--factor", "friction_pp:0.3:1.0",
                       "--automatic", "--max-iterations", "1", "--start", "--json")
    assert code == 0
    cid = json.loads(out)["id"]
    code, _, err = run(capsys, "campaign", "continue", str(cid), "--url", url)
    assert code == 2 and "HTTP 409" in err  # still running
    runner = CampaignRunner(app.state.session_factory, settings)
    for _ in range(12):
        runner.tick()
        drain(app, settings)
    code, out, _ = run(capsys, "campaign", "status", str(cid), "--url", url)
    assert code == 0 and "completed" in out and "maximum number of iterations reached" in out
    assert f"more iterations could go on from here: demcal campaign continue {cid}" in out
    code, _, err = run(capsys, "campaign", "continue", str(cid), "--url", url, "--iterations", "10")
    assert code == 2 and "HTTP 422" in err and "more_iterations" in err
    code, out, _ = run(capsys, "campaign", "continue", str(cid), "--url", url)
    assert code == 0 and f"campaign {cid} continues after iteration 1 (limit now 2" in out
    assert "maximum number of iterations reached" in out and "iteration 2 adds " in out
    assert any(name in out.split("iteration 2 adds ")[1] for name in ("rolling_epsd2", "particle_shape"))


def test_campaign_retry_of_a_campaign_that_did_not_fail_is_a_message(server, capsys):
    url, app, settings = server
    code, out, _ = run(capsys, "campaign", "create", "--url", url, "--name", "fine", "--material", "1",
                       "--evaluator", "analytic", "--fidelity", "thesis", "--factor", "friction_pp:0.3:1.0", "--json")
    cid = json.loads(out)["id"]
    code, _, err = run(capsys, "campaign", "retry", str(cid), "--url", url)
    assert code == 2 and "HTTP 409" in err and "only a failed campaign is retried" in err


def test_the_report_says_why_it_polished_and_prints_each_anchor(capsys, monkeypatch):
    """``demcal campaign report`` on an iteration polished for a missed prior (session 37): the polish line says
    why and where the Jacobian came from, and each anchor gets a line of its own. The report is the library
    loop's in tier A seed 13's Hertz world (tests/service/polish_case.py), served in place of the HTTP call."""
    from polish_case import hertz_polish, hertz_report

    import service.cli_campaigns as cli
    from service.cli_http import fmt

    served = {**hertz_report(), "polish": hertz_polish(), "campaign_id": 7, "iteration": 2}
    monkeypatch.setattr(cli, "_call", lambda args, method, path, **kw: served if path == "/campaigns/7/report" else None)
    code, out, _ = run(capsys, "campaign", "report", "7", "--url", "http://127.0.0.1:9")
    assert code == 0, out
    polish = served["polish"]
    head = next(line for line in out.splitlines() if line.startswith("polishing on the batteries: "))
    assert "Jacobian from the batteries" in head and head.endswith(f"why: {polish['why']}")
    # the polish took steps: the chosen point ran again at fresh seeds, and the report reads those (session 41)
    held = next(line for line in out.splitlines() if line.startswith("  held out: "))
    assert held == (f"  held out: the chosen point again at {len(polish['holdout_seeds'])} fresh seed(s), chi2 "
                    f"{fmt(polish['holdout_chi2'])}; the report reads these batteries")
    anchors = [line.strip() for line in out.splitlines() if line.startswith("  held at the measured ")]
    assert len(anchors) == len(polish["anchors"])
    for line, anchor in zip(anchors, polish["anchors"]):
        assert all(name in line for name in anchor["held"]), line
        assert ("the steps started there" in line) == bool(anchor.get("taken")), line
        if anchor.get("step_chi2") is not None:
            assert "one step from it: chi2 " in line
            assert line.endswith("the polish went on from there") == bool(anchor.get("step_taken")), line


def test_the_report_prints_each_parameter_s_interval_its_widening_and_the_trade(capsys, monkeypatch):
    """``demcal campaign report`` shows what the page's Parameters card shows (issue 33 item 3): each free
    parameter's interval, which one points measured on the batteries widened (with the surfaces' interval it
    replaced), and each pair that trades. The intervals are tests/service/intervals_case.py's (tier A seed 11's
    rolling world, its friction_pp-rolling trade), served in place of the HTTP call."""
    from intervals_case import trading_intervals
    from polish_case import hertz_report

    import service.cli_campaigns as cli
    from service.cli_http import fmt

    intervals = trading_intervals()
    served = {**hertz_report(), "intervals": intervals, "campaign_id": 7, "iteration": 2}
    monkeypatch.setattr(cli, "_call", lambda args, method, path, **kw: served if path == "/campaigns/7/report" else None)
    code, out, _ = run(capsys, "campaign", "report", "7", "--url", "http://127.0.0.1:9")
    assert code == 0, out
    lines = out.splitlines()
    assert "parameters, 95 % intervals:" in lines
    for name, row in intervals["parameters"].items():
        line = next(x for x in lines if x.startswith(name + " "))
        assert f"[{fmt(row['low'])}, {fmt(row['high'])}]" in line, line
    (name,) = intervals["measured_points"]["widened"]
    wald = intervals["parameters"][name]["wald"]
    line = next(x for x in lines if x.startswith(name + " "))
    assert f"widened to the points measured on the batteries (the surfaces' alone: [{fmt(wald['low'])}, " in line
    assert [x for x in lines if x.startswith("trade: ")] == [f"trade: {t['message']}" for t in intervals["trades"]]
