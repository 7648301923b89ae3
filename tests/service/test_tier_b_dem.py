"""Tier B on the DEM engine, in the reduced form CI can afford (slow): one hidden effect, end to end.

`bench/diagnosis_dem.py --reduced --scenarios rolling` starts a live `demcal serve` with two local
workers; the engine, with EPSD2 rolling resistance (mu_r 0.15) switched on, is the measuring world at
three seeds the calibration never uses, plus laboratory scatter and a pycnometer prior 2 % off; then one
automatic campaign runs the 2^(4-1) design with 3 centre runs, the confirmation, the diagnosis, the top
candidate added as a fifth factor and its confirmation, every battery a DEM job through the queue.
Reduced: 35 mm spheres (about 130 bodies in Appendix A's container), so a battery costs about a quarter
of a screening one, polished only where the surfaces miss the batteries (the service's default); and two
iterations (the first effect added and judged), since every criterion is settled by then and a third
iteration nearly doubled the batteries (51 -> 92).

Asked: the issue's pass criteria for the scenario. The model without the effect cannot follow the
measurements (the lack of fit rejects), the diagnosis names it among its first two candidates, adding it
brings the weighted error within 1.1 x the truth's own with chi2/dof <= 2 (issue 33's criterion for an effect
of this strength, lambda ~ 30; halving is asked of the strong scenarios, and here the truth's own error is
about the error before, so no right calibration could halve it), and particle density comes back within 5 %
of the truth. The truth's own error is the measuring world's parameters run at the calibration's seeds and
judged the same way (`--truth-floor`).
And one loop: `--replay` runs the campaign's stored batteries through the notebook loop
(`calibration.loop`), which must reproduce what the service stored.
On 40 mm spheres the error fell only to 0.59 (docs/diagnosis.md), so the reduced form stops at 35 mm.
The full tier B (20 mm spheres, polish, the issue's pass table) is `python3 bench/diagnosis_dem.py`,
hours.
"""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow
ROOT = Path(__file__).resolve().parents[2]


def test_hidden_rolling_resistance_is_found_on_the_dem_engine(tmp_path):
    out = subprocess.run(
        [sys.executable, str(ROOT / "bench" / "diagnosis_dem.py"), "--reduced", "--scenarios", "rolling",
         "--workers", "2", "--max-iterations", "2", "--truth-floor", "--replay"],
        capture_output=True, text=True, timeout=2400, cwd=tmp_path)
    print(out.stdout)
    assert out.returncode == 0, out.stderr[-2000:]
    lines = out.stdout.strip().splitlines()
    figures = dict(item.split("=", 1) for item in lines[-1].split())
    assert figures["form"] == "reduced" and figures["evaluator"] == "dem", lines[-1]
    assert figures["n_effects"] == "1" and figures["n_null"] == "0", out.stdout
    (row,) = [line for line in lines if line.startswith("rolling ")]
    # every battery of the scenario went through the queue: 3 measuring + 11 design + 1 confirmation at
    # least, and more for the diagnosis and the second iteration
    assert int(re.search(r"batteries=(\d+)", row).group(1)) > 15, row
    # the pass criteria for this scenario
    assert figures["lof_rejects_effects"] == "1", out.stdout
    assert figures["true_top2"] == "1", out.stdout
    assert "added=rolling_epsd2" in row, row
    assert figures["within_truth_floor"] == "1" and figures["n_truth_floor"] == "1", out.stdout
    # the same criterion read off the row: at the kept fit's own seeds, within 1.1 x the error the measuring
    # world's own parameters reach there. Not 1.0 x: where the surfaces predict the confirmation batteries the
    # service does not polish, and the surfaces' optimum may sit a little above the batteries' (session 34's
    # draw: 0.875 against the truth's 0.856; with two polish steps in session 34's other draw, 0.646 against 1.02)
    after, truth = map(float, re.search(r"rms=[\d.]+ -> ([\d.]+) \([^;]*; truth [\d.]+, at the kept fit's seeds "
                                        r"([\d.]+)[;)]", row).groups())
    assert after <= 1.1 * truth, row
    assert figures["density_within_5pc"] == "1", out.stdout
    # one loop: the campaign's stored DEM batteries replayed through the notebook loop give the service's
    # verdicts, optimum (relative 1e-9), rankings, added effect and stop reason
    assert figures["replay_same"] == "1" and figures["n_replayed"] == "1", out.stdout
