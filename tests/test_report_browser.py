"""The reports in a real browser: headless Chromium (the distribution's package) opens the
``report.html`` of ``hip run``, ``pdm run``, ``hip control`` and of a described mechanism's
``run --machine stewart``, and the ``view`` page, and checks that nothing
fails on the console, that the 3D view draws the mechanism and waits for its play button, that
moving the time slider moves it (and the time marker of every plot), that play and pause work,
and that every plot is there.

Screenshots are written under pytest's ``tmp_path``, never into the repository. Without
Playwright or a Chromium binary the tests are skipped on a developer's machine and fail under
CI (``CI`` set), where ``.ci/run`` installs both.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from pkmdyn.cli import main

#: the pages' drawing does not depend on the BLAS kernel: CI runs these once (pyproject.toml, slow)
pytestmark = pytest.mark.slow

sync_api = pytest.importorskip("playwright.sync_api")
Image = pytest.importorskip("PIL.Image")

_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
#: the colour of the links in the 3D view (report._figures._LINK)
_LINK = np.array([0x34, 0x49, 0x5E])
#: the browser window: a small laptop's. Software WebGL (SwiftShader) draws every pixel of the 3D
#: view and of its picking buffer on the CPU, so the pages' time grows with the window's area
_VIEWPORT = {"width": 1024, "height": 700}


def _chromium() -> str:
    given = os.environ.get("PKMDYN_CHROMIUM")
    found = given or next((p for p in map(shutil.which, _NAMES) if p), None)
    if found is None:
        message = "no Chromium binary (install the distribution's chromium package, or set PKMDYN_CHROMIUM)"
        if os.environ.get("CI") or os.environ.get("PKMDYN_REQUIRE_OPTIONAL"):
            pytest.fail(f"required under CI: {message}")
        pytest.skip(message)
    return found


@pytest.fixture(scope="module")
def browser():
    exe = _chromium()
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=exe, headless=True,
                              args=["--enable-unsafe-swiftshader", "--use-angle=swiftshader", "--no-sandbox"])
        yield b
        b.close()


@pytest.fixture(scope="module")
def reports(tmp_path_factory):
    d = tmp_path_factory.mktemp("reports")
    assert main(["hip", "run", "--samples-per-cycle", "400", "--out", str(d / "hip")]) == 0
    assert main(["pdm", "run", "--out", str(d / "pdm")]) == 0
    assert main(["hip", "control", "--controller", "augmented-pd", "--cycles", "0.4", "--out", str(d / "ctl")]) == 0
    assert main(["view", "--machine", "pdm", "--out", str(d / "view_pdm.html")]) == 0
    assert main(["run", "--machine", "stewart", "--out", str(d / "stewart")]) == 0
    assert main(["control", "--machine", "stewart", "--duration", "0.3", "--out", str(d / "stewart_ctl")]) == 0
    return {"hip": d / "hip" / "report.html", "pdm": d / "pdm" / "report.html", "hip_control": d / "ctl" / "report.html",
            "view": d / "view_pdm.html", "stewart": d / "stewart" / "report.html",
            "stewart_control": d / "stewart_ctl" / "report.html"}


class _Page:
    """A page opened in the browser, with every console error and uncaught exception recorded."""

    def __init__(self, browser, path: Path) -> None:
        self.errors: list[str] = []
        self.page = browser.new_page(viewport=_VIEWPORT)
        self.page.set_default_timeout(120_000)  # every action on a page drawn in software (below)
        self.page.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)
        self.page.on("pageerror", lambda e: self.errors.append(f"uncaught: {e}"))
        try:
            # a multi-megabyte page parsed and drawn in software (SwiftShader) on two cores: the hip's
            # report takes about 30 s to its load event, Playwright's default navigation limit
            self.page.goto(path.as_uri())
            self.page.wait_for_function("window.PKMDYN_REPORT && window.PKMDYN_REPORT.ready === true",
                                        timeout=120_000)
            # the 3D scene is drawn once its WebGL canvas exists
            self.page.wait_for_selector("#pkmdyn-scene .gl-container canvas", state="attached", timeout=120_000)
        except Exception:
            self.page.close()  # a page left open keeps drawing and slows every page after it
            raise
        self.page.wait_for_timeout(500)

    def scene_shot(self, path: Path) -> np.ndarray:
        """The 3D plot area: the scene's box without the legend (left), the colour bar (right),
        the title (top) and the play buttons and slider (bottom)."""
        self.page.locator("#pkmdyn-scene").scroll_into_view_if_needed()
        box = self.page.locator("#pkmdyn-scene").bounding_box()
        clip = {"x": box["x"] + 0.16 * box["width"], "y": box["y"] + 0.08 * box["height"],
                "width": 0.66 * box["width"], "height": 0.72 * box["height"]}
        self.page.screenshot(path=str(path), clip=clip)
        return np.asarray(Image.open(path).convert("RGB")).astype(int)

    def info(self) -> dict:
        return self.page.evaluate("window.PKMDYN_REPORT")


def _link_pixels(img: np.ndarray) -> int:
    return int(np.sum(np.abs(img - _LINK).sum(axis=-1) < 40))


def _distinct(img: np.ndarray) -> int:
    return len(np.unique(img.reshape(-1, 3), axis=0))


@pytest.mark.parametrize("which, n_plots, n_images, parameters", [
    ("hip", 11, 7, "[geometry]"), ("pdm", 9, 5, "[geometry]"), ("hip_control", 2, 2, "[geometry]"),
    ("stewart", 6, 0, "[[legs.joints]]"), ("stewart_control", 2, 2, "[[legs.joints]]")])
def test_report_draws_moves_and_shows_every_plot(browser, reports, tmp_path, which, n_plots, n_images, parameters):
    page = _Page(browser, reports[which])
    try:
        info = page.info()
        assert info["frames"] > 100 and len(info["plots"]) == n_plots
        first = page.scene_shot(tmp_path / f"{which}_first.png")
        assert _distinct(first) > 50, "the 3D view is blank"
        assert page.info().get("current") is None, "the 3D view played before its play button was pressed"
        assert _link_pixels(first) > 300, "the 3D view shows no links of the mechanism"

        # move the time slider as a user does: a click on its rail, 80 % along
        rail = page.page.locator("#pkmdyn-scene .slider-rail-rect").bounding_box()
        page.page.mouse.click(rail["x"] + 0.8 * rail["width"], rail["y"] + 0.5 * rail["height"])
        page.page.wait_for_function("window.PKMDYN_REPORT.current > 0", timeout=60_000)
        page.page.wait_for_timeout(1000)
        k = page.info()["current"]
        assert 0.7 * info["frames"] < k < 0.9 * info["frames"]
        second = page.scene_shot(tmp_path / f"{which}_second.png")
        changed = np.abs(first - second).sum(axis=-1) > 30
        assert changed.sum() > 200, "moving the time slider did not move the mechanism"
        assert _link_pixels(second) > 300

        # every plot is drawn, with curves, and its time marker follows the slider
        marks = page.page.evaluate("""window.PKMDYN_REPORT.plots.map(function (id) {
            var el = document.getElementById(id);
            return [el.data.length, el.querySelectorAll('.scatterlayer .trace').length, el.layout.shapes[0].x0];
        })""")
        t_k = info["times"][k]
        for n_traces, drawn, x0 in marks:
            assert n_traces > 0 and drawn > 0
            assert x0 == pytest.approx(t_k)
        assert page.page.locator("#figures img").count() == n_images
        assert page.page.locator("#summary table").count() >= 1
        assert parameters in page.page.locator("#parameters pre").inner_text()

        # the play button plays on from the slider's frame, and pause stops it
        buttons = page.page.locator("#pkmdyn-scene .updatemenu-button")
        buttons.filter(has_text="\u00d74").click()
        page.page.wait_for_function(f"window.PKMDYN_REPORT.current > {k}", timeout=60_000)
        buttons.filter(has_text="pause").click()
        page.page.wait_for_timeout(1000)
        stopped = page.info()["current"]
        page.page.wait_for_timeout(1000)
        assert page.info()["current"] == stopped, "pause did not stop the playback"
        assert not page.errors, page.errors
    finally:
        page.page.close()


def test_view_page_draws_the_machine_and_its_topology(browser, reports, tmp_path):
    page = _Page(browser, reports["view"])
    try:
        shot = page.scene_shot(tmp_path / "view.png")
        assert _distinct(shot) > 50 and _link_pixels(shot) > 300
        edges = page.page.evaluate("document.getElementById('pkmdyn-topology').data.length")
        assert edges >= 19  # one trace per joint, plus labels and bodies
        text = page.page.locator("#mobility").inner_text()
        assert "independent loops" in text and "over-constraints (screw theory)" in text
        assert not page.errors, page.errors
    finally:
        page.page.close()


@pytest.mark.parametrize("width", [1000, 1400, 1920])
def test_every_time_plot_fits_its_cell(browser, reports, width):
    """At every window width each time plot is drawn within its cell (in a window wide enough for
    two columns the first one was drawn as wide as the whole grid, half of it cut off)."""
    page = browser.new_page(viewport={"width": width, "height": 600})
    try:
        page.set_default_timeout(120_000)
        page.goto(reports["stewart"].as_uri())
        page.wait_for_function("window.PKMDYN_REPORT && window.PKMDYN_REPORT.ready === true", timeout=120_000)
        page.wait_for_timeout(1000)
        sizes = page.evaluate("""window.PKMDYN_REPORT.plots.map(function (id) {
            var el = document.getElementById(id), cell = el.closest('.timeplot');
            return [el.querySelector('.main-svg').getBoundingClientRect().width,
                    cell.getBoundingClientRect().width, cell.parentElement.getBoundingClientRect().width];
        })""")
        assert len(sizes) >= 2
        for drawn, cell, grid in sizes:
            if width >= 1400:  # two columns of plots: the case that went wrong
                assert cell < 0.75 * grid, "the grid has one column: the window is not wide enough for the check"
            assert drawn <= cell + 1, f"a plot {drawn:.0f} px wide in a {cell:.0f} px cell"
    finally:
        page.close()
