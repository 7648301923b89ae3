"""The rigs page: the bundled rigs listed and read, and the material page naming the rig it was measured in."""
from __future__ import annotations

from test_browser import browser, expect_text, open_view, page, pytestmark, service, shots  # noqa: F401


def test_rigs_are_listed_and_read_and_the_material_names_its_rig(page, service):
    open_view(page, service, "#/rigs")
    expect_text(page, "h2", "Rigs")
    listing = page.locator("main").inner_text()
    assert "thesis-590mm-shear-box" in listing and "appendix-a-400mm-shear-box" in listing
    assert "590 mm across" in listing and "400 mm across" in listing
    page.locator("a", has_text="thesis-590mm-shear-box").click()
    expect_text(page, "h2", "thesis-590mm-shear-box")
    expect_text(page, "main", "container_diameter_m")
    assert "Bundled record, read-only." in page.locator("main").inner_text()
    open_view(page, service, "#/materials/1")
    expect_text(page, "p.rig", "Measured in rig thesis-590mm-shear-box")
    page.locator("p.rig a").click()
    expect_text(page, "h2", "thesis-590mm-shear-box")
