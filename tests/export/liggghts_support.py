"""Skip a test when Debian's liggghts is missing, except under DEMCAL_REQUIRE_LIGGGHTS=1 (set by .ci/run),
where its absence is a failure: CI must run these tests, not skip them."""
from __future__ import annotations

import os

import pytest

from calibration.export.rig_liggghts import REQUIRE_ENV, liggghts_executable


def require_liggghts() -> str:
    exe = liggghts_executable()
    if exe is None:
        if os.environ.get(REQUIRE_ENV) == "1":
            pytest.fail(f"{REQUIRE_ENV}=1 but liggghts is not installed (apt-get install -y liggghts)")
        pytest.skip("liggghts not installed (apt-get install -y liggghts)")
    return exe
