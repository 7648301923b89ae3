"""`demcal doe design|analyze` through register() on a tiny parser, as service.cli will call it."""
import argparse
import csv
import io
import json
import subprocess
import sys
from pathlib import Path

import pytest

from doe import cli

DATA = json.loads((Path(__file__).parent / "thesis_appendix_a.json").read_text())
FOUR = ["--factor", "rho_p:2000:20000:kg/m3", "--factor", "mu_pp:0.05:0.5", "--factor", "mu_pw:0.01:0.045",
        "--factor", "k_p:1e6:2e6:N/m"]


def run(argv, capsys):
    parser = argparse.ArgumentParser(prog="demcal")
    subs = parser.add_subparsers(dest="command", required=True)
    cli.register(subs)
    args = parser.parse_args(argv)
    code = args.func(args)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_design_csv_parses_with_natural_coded_and_aliases(capsys):
    code, out, err = run(["doe", "design", *FOUR, "--generators", "D=ABC", "--center", "3", "--seed", "5",
                          "--format", "csv"], capsys)
    assert code == 0 and err == ""
    comments = [ln for ln in out.splitlines() if ln.startswith("#")]
    assert "# I = ABCD" in comments and "# BC = AD" in comments
    rows = list(csv.DictReader(io.StringIO("\n".join(ln for ln in out.splitlines() if not ln.startswith("#")))))
    assert len(rows) == 11
    assert sum(r["point_type"] == "center" for r in rows) == 3
    assert len({r["seed"] for r in rows}) == 11
    first = rows[0]
    assert float(first["rho_p"]) == 2000 and float(first["A_coded"]) == -1 and float(first["k_p"]) == 1e6
    assert sorted(int(r["run_order"]) for r in rows) == list(range(1, 12))


def test_design_json_and_text(capsys):
    code, out, _ = run(["doe", "design", *FOUR, "--format", "json", "--ccd", "face"], capsys)
    d = json.loads(out)
    assert code == 0 and d["aliases"]["resolution"] == 4 and d["generators"] == ["D=ABC"]
    assert sum(r["point_type"] == "axial" for r in d["runs"]) == 8
    code, out, _ = run(["doe", "design", *FOUR[:4], "--full", "--center", "2"], capsys)
    assert code == 0 and "2^2 full factorial" in out and "Std" in out


def _write_a9(tmp_path):
    path = tmp_path / "a9.csv"
    runs = DATA["table_A9_responses"]["runs"]
    with path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(runs[0]))
        w.writeheader()
        w.writerows(runs)
    return path


def test_analyze_thesis_table_a9(tmp_path, capsys):
    path = _write_a9(tmp_path)
    code, out, err = run(["doe", "analyze", str(path), "--factors", "rho_p,mu_pp,mu_pw,k_p",
                          "--responses", "bulk_density,phi_deg", "--json"], capsys)
    assert code == 0, err
    res = json.loads(out)
    eff = {e["term"]: e["effect"] for e in res["responses"]["bulk_density"]["effects"]["effects"]}
    for term, printed in DATA["table_A10_effects"]["bulk_density"].items():
        assert eff[term] == pytest.approx(float(printed), abs=0.005)
    nat = {c["name"]: c["estimate"] for c in res["responses"]["bulk_density"]["coefficients_natural"]}
    assert nat["k_p"] == pytest.approx(-38.55)           # k_p column is in MN/m in the CSV
    assert res["responses"]["phi_deg"]["has_error_estimate"] is False
    assert all(r["p_value"] is None for r in res["responses"]["phi_deg"]["anova"])
    code, out, _ = run(["doe", "analyze", str(path), "--factors", "rho_p,mu_pp,mu_pw,k_p",
                        "--responses", "bulk_density"], capsys)
    assert code == 0 and "ANOVA" in out and "No error estimate" in out and "BC = AD" in out


@pytest.mark.parametrize("argv,msg", [
    (["doe", "design", "--factor", "a:1:0"], "must be below"),
    (["doe", "design", "--factor", "a:x:1"], "must be numbers"),
    (["doe", "design", *FOUR, "--generators", "D=ABQ"], "unknown factor letter"),
    (["doe", "design", *FOUR, "--foldover", "nope"], "no factor named"),
])
def test_bad_design_input_exit_2(argv, msg, capsys):
    code, out, err = run(argv, capsys)
    assert code == 2 and msg in err and "Traceback" not in err and out == ""


def test_bad_analyze_input_exit_2(tmp_path, capsys):
    path = _write_a9(tmp_path)
    code, _, err = run(["doe", "analyze", str(path), "--factors", "rho_p,nope", "--responses", "phi_deg"], capsys)
    assert code == 2 and "'nope' not in" in err
    code, _, err = run(["doe", "analyze", str(tmp_path / "missing.csv"), "--factors", "a", "--responses", "b"],
                       capsys)
    assert code == 2 and "cannot read" in err
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b,y\n0,0,1\n1,x,2\n")
    code, _, err = run(["doe", "analyze", str(bad), "--factors", "a,b", "--responses", "y"], capsys)
    assert code == 2 and "not a number" in err


def test_main_and_module_entry_point_exit_codes(capsys):
    assert cli.main(["doe", "design", "--factor", "a:0:1", "--factor", "b:0:1", "--format", "json"]) == 0
    assert json.loads(capsys.readouterr().out)["n_runs"] == 4
    bad = subprocess.run([sys.executable, "-m", "doe.cli", "doe", "design", "--factor", "a:1:1"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "error:" in bad.stderr and "Traceback" not in bad.stderr
