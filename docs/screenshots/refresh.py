"""Refresh the screenshots of every view in docs/screenshots/ (linked from the README).

Why the browser tests take them: the tests already walk every view on a live service with real data
(an analytic campaign through two iterations, jobs, a recorded DEM battery, forms with errors, the API
docs, a missing page), so the pictures show what the tests checked. Viewport-sized (1280x900) pictures
of whole pages and card-sized ones of the campaign's sections keep the files small.

    python3 docs/screenshots/refresh.py        # needs chromium and playwright (pip install -e '.[test]')
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
DUPLICATES = ("test_api_docs_work_offline.png", "test_bad_field_is_shown_beside_its_input.png",
              "test_campaign_loop_create_start_diagnose_add_effect_error_falls.png")


def main() -> int:
    for old in HERE.glob("*.png"):
        old.unlink()
    env = dict(os.environ, DEMCAL_SCREENSHOT_DIR=str(HERE), DEMCAL_SCREENSHOT_FULL_PAGE="0", DEMCAL_REQUIRE_BROWSER="1")
    run = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "tests/service/test_browser.py"],
                         cwd=ROOT, env=env)
    for duplicate in DUPLICATES:  # a test's last state that a named picture already shows
        (HERE / duplicate).unlink(missing_ok=True)
    shots = sorted(HERE.glob("*.png"))
    for shot in shots:
        print(f"{shot.stat().st_size / 1024:7.0f} KiB  {shot.relative_to(ROOT)}")
    return run.returncode or (0 if shots else 1)


if __name__ == "__main__":
    sys.exit(main())
