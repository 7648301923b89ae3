"""The campaign form picks a resolution (issue 29): the thesis aggregate coarse-grained x 2 in its own rig, and the
campaign page says what that costs in validity (the standards' warning) where the user reads it."""
from __future__ import annotations

import re

from test_browser import browser, expect_text, open_view, page, pytestmark, service, shots  # noqa: F401


def test_the_campaign_form_runs_a_coarse_resolution_in_the_materials_rig(page, service):
    open_view(page, service, "#/campaigns")
    form = page.locator("form#new-campaign")
    form.locator("input[name=name]").fill("browser coarse")
    form.locator("select[name=material_id]").select_option(label="thesis-coarse-aggregate")
    form.locator("select[name=evaluator]").select_option("analytic")
    form.locator("select[name=resolution]").select_option("coarse")
    form.locator("input[name=scale_factor]").fill("2")
    form.get_by_role("button", name="Create (draft)").click()
    page.wait_for_url(re.compile(r"#/campaigns/\d+$"))
    expect_text(page, "h2", "browser coarse")
    assert "coarse" in page.locator("main table").first.inner_text()
    # the cost where it runs (the count itself is checked against the cost model in test_resolution_api)
    expect_text(page, "p.campaign-estimate", r"about [\d,]+ particles.*in rig thesis-590mm-shear-box at resolution "
                                             r"coarse \(sizes x 2\)")
    # 84 mm grains in the 590 mm box: 7.0 across, accepted with the direct-shear standards' warning
    expect_text(page, "ul.campaign-warnings", "7.0 largest particles")
