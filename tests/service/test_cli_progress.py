"""The CLI's answers a user judges progress and results by (issue 31): a phase's own run count with a
progress bar, --watch, the echo of the iteration ``iterate`` starts, the diagnosis's message and
strength units, one rule for the service's URL, ids for scripts, replicate lists as people type them."""
from __future__ import annotations

import argparse
import json
import re

import pytest
from conftest_s2 import drain
from test_campaign_cli import run, server  # noqa: F401  (the live-server fixture)

from service.campaigns.runner import CampaignRunner
from service.cli_http import CliError, service_url

THREE = ("--factor", "particle_density_kg_m3:2300:2700", "--factor", "particle_stiffness_n_per_m:1e6:3e6",
         "--factor", "friction_pp:0.3:1.0")


def _create(capsys, url, *extra) -> int:
    code, out, err = run(capsys, "campaign", "create", "--url", url, "--name", f"c{len(extra)}", "--material", "1",
                         "--evaluator", "analytic", "--fidelity", "thesis", *THREE, "--centre-runs", "3", *extra, "-q")
    assert code == 0, err
    return int(out)  # -q: the id alone


def _polish_summary(capsys, url, cid) -> dict:
    code, out, err = run(capsys, "campaign", "report", str(cid), "--url", url, "--json")
    assert code == 0, err
    return json.loads(out).get("polish") or {}


def _status(capsys, url, cid) -> str:
    code, out, err = run(capsys, "campaign", "status", str(cid), "--url", url)
    assert code == 0, err
    return out


def test_status_shows_each_phase_s_own_runs_and_watch_ends_with_the_campaign(server, capsys):  # noqa: F811
    url, app, settings = server
    cid = _create(capsys, url, "--polish-when", "always", "--start")  # every phase shown, polishing included
    runner = CampaignRunner(app.state.session_factory, settings)
    runner.tick()  # the design: 2^3 + 3 centre runs queued
    assert "phase batteries: design runs [" + "." * 24 + "] 0/11" in _status(capsys, url, cid)
    drain(app, settings, max_jobs=4)
    runner.tick()  # the runs take their jobs' states
    assert "design runs [#########...............] 4/11" in _status(capsys, url, cid)
    drain(app, settings)
    runner.tick()  # analysis -> confirmation at two seeds (the default)
    runner.tick()
    out = _status(capsys, url, cid)
    assert "phase confirmation: confirmation seeds [" in out and "] 0/2" in out  # not x/13: the phase's own
    seen = set()
    for _ in range(20):
        drain(app, settings)
        runner.tick()
        out = _status(capsys, url, cid)
        if "phase polish: polish round " in out:  # a round's own runs, the round numbered
            seen.add("polish")
            assert re.search(r"polish round \d+ \[[#.]{24}\] 0/\d+", out), out
        if "phase polish: held-out confirmation [" in out:  # the chosen point at fresh seeds, after a step
            seen.add("holdout")
            assert "held-out confirmation [" + "." * 24 + "] 0/2" in out, out
        if "phase diagnosis: diagnosis batteries [" in out:
            seen.add("diagnosis")
            code, _, err = run(capsys, "campaign", "diagnose", str(cid), "--url", url)
            assert code == 2 and "not done yet (phase diagnosis)" in err
        if "completed" in out:
            break
    # the polish took a step here (the surfaces' optimum is not the stand-in's), so the held-out round ran
    polished = _polish_summary(capsys, url, cid)
    assert polished["steps"] >= 1 and len(polished["holdout_seeds"]) == 2
    assert seen == {"polish", "holdout", "diagnosis"} and "completed" in out
    code, out, _ = run(capsys, "campaign", "status", str(cid), "--url", url, "--watch", "--interval", "0.05")
    assert code == 0 and out.count("\n") == 1 and "completed, iteration 1, phase done" in out

    # the diagnosis's strengths carry their units; none is printed as a negative energy
    code, out, _ = run(capsys, "campaign", "diagnose", str(cid), "--url", url)
    assert code == 0 and " J/m2 " in out and " Pa " in out
    code, out, _ = run(capsys, "campaign", "diagnose", str(cid), "--url", url, "--json")
    strengths = {r["effect"]: r["strength"] for r in json.loads(out)["ranking"]}
    assert strengths["rolling_epsd2"] > 0  # unit "1": printed bare

    # iterate echoes the iteration it starts, not the finished one, with the factor the effect adds
    code, out, _ = run(capsys, "campaign", "iterate", str(cid), "--url", url, "--add-effect", "rolling_epsd2")
    assert code == 0
    assert out.startswith(f"campaign {cid}: iteration 2 running, with rolling_epsd2 added\n")
    assert "new factor: effects.rolling_epsd2.rolling_friction 0.." in out and "factors (4):" in out
    assert "starting iteration 2" in _status(capsys, url, cid)


def test_diagnosis_of_a_finished_iteration_that_ran_none_says_so(server, capsys, tmp_path):  # noqa: F811
    url, app, settings = server
    body = tmp_path / "no-diagnosis.json"
    body.write_text(json.dumps({"diagnose": False}))
    cid = _create(capsys, url, "--file", str(body), "--start")
    runner = CampaignRunner(app.state.session_factory, settings)
    for _ in range(6):
        runner.tick()
        drain(app, settings)
    assert "completed" in _status(capsys, url, cid)
    code, _, err = run(capsys, "campaign", "diagnose", str(cid), "--url", url)
    assert code == 2 and "finished ('targets out of reach') without one" in err and "not done" not in err


def test_job_ids_for_scripts_and_watch(server, capsys):  # noqa: F811
    url, app, settings = server
    code, out, _ = run(capsys, "job", "submit", "--url", url, "--test", "dst", "--evaluator", "analytic", "-q")
    job = int(out)
    drain(app, settings)
    code, out, _ = run(capsys, "job", "status", str(job), "--url", url, "--watch", "--interval", "0.05")
    assert code == 0 and f"job {job}: succeeded" in out
    code, _, err = run(capsys, "job", "status", str(job), "--url", url, "--watch", "--json")
    assert code == 2 and "--watch" in err
    with pytest.raises(SystemExit) as refused:  # argparse: not a sensible poll period
        run(capsys, "job", "status", str(job), "--url", url, "--watch", "--interval", "0")
    assert refused.value.code == 2 and "between 0.05 and 3600 seconds" in capsys.readouterr().err


def test_replicates_with_a_decimal_comma_and_the_ambiguous_refused(server, capsys):  # noqa: F811
    url, _, _ = server
    mid, other = (run(capsys, "material", "create", "--url", url, "--name", name, "-q")[1].strip()
                  for name in ("gravel", "sand"))
    add = ("material", "add-measurement", mid, "--url", url, "--test", "fill", "--quantity", "bulk_density_kg_m3")
    code, out, _ = run(capsys, *add, "--values", "1397,8")
    assert code == 0 and "1 replicate(s), mean 1397.8 kg/m3" in out  # one value, not 1397 and 8
    code, out, err = run(capsys, *add[:2], other, *add[3:], "--values", "1412;1383,6\n1397.8",
                         "--json")
    assert code == 0, err
    assert json.loads(out)["values"] == pytest.approx([1412.0, 1383.6, 1397.8])
    code, out, err = run(capsys, *add, "--values", "1,397")
    assert code == 2 and out == "" and err.startswith("demcal: --values: '1,397' is ambiguous")


@pytest.mark.parametrize("url,env,expected", [
    ("http://a:1/", {"DEMCAL_URL": "http://b:2", "DEMCAL_PORT": "3"}, ("http://a:1", "--url")),
    (None, {"DEMCAL_URL": "http://b:2/", "DEMCAL_PORT": "3"}, ("http://b:2", "DEMCAL_URL")),
    (None, {"DEMCAL_PORT": "8123"}, ("http://127.0.0.1:8123", "DEMCAL_PORT")),
    (None, {"DEMCAL_HOST": "0.0.0.0", "DEMCAL_PORT": "81"}, ("http://127.0.0.1:81", "DEMCAL_HOST and DEMCAL_PORT")),
    (None, {"DEMCAL_HOST": "::1"}, ("http://[::1]:8000", "DEMCAL_HOST")),
    (None, {}, ("http://127.0.0.1:8000", "the default")),
])
def test_one_base_url_rule(monkeypatch, url, env, expected):
    for name in ("DEMCAL_URL", "DEMCAL_HOST", "DEMCAL_PORT"):
        monkeypatch.delenv(name, raising=False)
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    assert service_url(argparse.Namespace(url=url)) == expected


def test_a_port_that_is_no_port_is_a_message(monkeypatch, capsys):
    monkeypatch.delenv("DEMCAL_URL", raising=False)
    monkeypatch.setenv("DEMCAL_PORT", "80a")
    with pytest.raises(CliError, match="DEMCAL_PORT '80a' is not a port number; give --url"):
        service_url(argparse.Namespace(url=None))
    code, _, err = run(capsys, "material", "list")
    assert code == 2 and err.startswith("demcal: DEMCAL_PORT")
