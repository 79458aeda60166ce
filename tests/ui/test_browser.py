"""The results UI as a person sees it: ``simtest ui`` served for real, clicked through in
headless Chromium over the DevTools protocol (``tests/ui/cdp.py``).

Covers: the overview's totals and newest-run tiles; the navigation to history and flakiness,
where the scenario that changed verdict under the same seed is flagged ``nondeterministic`` and
its history page shows the mixed same-seed family; a run's scenario list (a retried pass shown as
"on attempt 2", never as a clean pass) and, one click further, the developer view: the reason,
the trajectory replay (a mouse press on the time slider moves the ego's and the cutter's markers
to their recorded positions at that time, read out in metres) and the cursor and value on the
metric timeline; the coverage page switched to requirements by a click; a comparison of two runs.
Screenshots of the views are real renderings (size, verdict colours present); with
``SIMTEST_UPDATE_SCREENSHOTS=1`` they are written to ``docs/`` for docs/ui.md.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from PIL import Image

from tests.ui.cdp import Browser
from tests.ui.conftest import SAMPLE_RUN

pytestmark = pytest.mark.browser

REPO = Path(__file__).resolve().parents[2]
DOCS = REPO / "docs"


@pytest.fixture(scope="module")
def base_url(ui_target: Path) -> Iterator[str]:
    """``simtest ui --database OUTDIR --port 0`` as a process; its URL."""
    process = subprocess.Popen(
        [sys.executable, "-c", "from simtest_operator.cli.main import main; main()", "ui",
         "--database", str(ui_target), "--port", "0"],
        stderr=subprocess.PIPE, text=True, cwd=REPO,
    )  # fmt: skip
    assert process.stderr is not None
    line = process.stderr.readline()
    found = re.search(r"on (http://127\.0\.0\.1:\d+/)", line)
    if found is None:
        process.kill()
        rest = process.stderr.read()
        process.wait()
        process.stderr.close()
        pytest.fail(f"simtest ui did not start: {line}{rest}")
    try:
        yield found.group(1)
    finally:
        process.terminate()
        process.wait(timeout=10)
        process.stderr.close()


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Browser]:
    with Browser(tmp_path_factory.mktemp("chromium") / "profile") as opened:
        yield opened


def _shot(browser: Browser, name: str, tmp_path: Path) -> Image.Image:
    target = DOCS if os.environ.get("SIMTEST_UPDATE_SCREENSHOTS") == "1" else tmp_path
    image = Image.open(browser.screenshot(target / f"ui-{name}.png")).convert("RGB")
    assert image.width == 1280 and image.height > 300
    return image


def _has_colour(image: Image.Image, hex_colour: str) -> bool:
    wanted = tuple(int(hex_colour[i : i + 2], 16) for i in (1, 3, 5))
    small = image.resize((image.width // 2, image.height // 2), Image.Resampling.NEAREST)
    colours = small.getcolors(maxcolors=1 << 20) or []
    return any(
        isinstance(rgb, tuple) and all(abs(c - w) <= 3 for c, w in zip(rgb, wanted, strict=True))
        for _, rgb in colours
    )


def test_overview_then_history_and_flakiness(
    browser: Browser, base_url: str, tmp_path: Path
) -> None:
    browser.open(base_url)
    assert browser.text("[data-total=runs]") == "9"
    assert browser.text("[data-total=scenarios]") == "14"
    assert browser.text("[data-count=Total]") == "1", "the newest run (8) ran one scenario"
    assert _has_colour(_shot(browser, "overview", tmp_path), "#2e9d5b")
    browser.click("header nav a[href='/history']")
    assert browser.evaluate("location.pathname") == "/history"
    assert browser.text("#flaky-count") == "5"  # 4 of the history + follow/stop (retried)
    flags = browser.evaluate(
        "Object.fromEntries([...document.querySelectorAll('#history tbody tr')]"
        ".map(r => [r.dataset.scenario, r.cells[1].innerText.trim()]))"
    )
    assert flags["nondet.xosc"] == "flaky: nondeterministic"
    assert flags["seedy.xosc"] == "flaky: seed-sensitive"
    assert flags["retry.xosc"] == "flaky: retried"
    assert flags["regress.xosc"] == "stable"
    _shot(browser, "history", tmp_path)
    browser.click("#history a[href*='nondet.xosc']")
    assert browser.text("#scenario-id") == "nondet.xosc"
    assert "the same seed gave different verdicts" in browser.text("#flakiness")
    assert browser.evaluate("document.querySelectorAll('#families tr.mixed').length") == 2
    assert browser.evaluate("document.querySelectorAll('#entries tbody tr').length") == 5


def test_developer_view_replays_the_recording(
    browser: Browser, base_url: str, tmp_path: Path
) -> None:
    browser.open(f"{base_url}run?run={SAMPLE_RUN}")
    follow = browser.evaluate(
        "document.querySelector('#scenarios tr[data-scenario=\"follow/stop.xosc\"]').innerText"
    )
    assert "Passed" in follow and "on attempt 2" in follow
    browser.click("#scenarios a.dev[href*='cut-in%2Fclose.xosc']")
    assert browser.text("#scenario-id") == "cut-in/close.xosc"
    assert browser.text("#reason") == "collision with 'cutter' at t=7.2 s"
    browser.wait_for("document.body.dataset.replay === 'ready'")
    assert browser.evaluate("document.querySelectorAll('#replay svg circle.marker').length") == 2
    start = browser.evaluate("document.querySelector('circle.marker.ego').getAttribute('cx')")
    # A mouse press 60 % along the slider: t = 6 s of the 10 s recording.
    browser.click("#replay-slider", at=0.6, navigates=False)
    t = float(browser.text("#replay-time"))
    assert 5.7 <= t <= 6.3
    rows = browser.evaluate(
        "Object.fromEntries([...document.querySelectorAll('#replay-readout tbody tr')]"
        ".map(r => [r.dataset.entity, [+r.cells[1].innerText, +r.cells[2].innerText]]))"
    )
    ego = rows.pop("ego")
    ((_, cutter),) = rows.items()  # named "object 1": the sample recording names no entities
    assert abs(ego[0] - 20.0 * t) < 0.3 and ego[1] == -1.8  # the ego at 20 m/s in its lane
    assert abs(cutter[0] - (25.0 + 15.0 * t)) < 0.3
    assert abs(cutter[1] - (-1.75 + 3.5 * max(0.0, 1 - (t - 3) / 3))) < 0.15
    moved = browser.evaluate("document.querySelector('circle.marker.ego').getAttribute('cx')")
    assert float(moved) > float(start) + 100, "the ego's marker moves along its path"
    assert browser.text(".timeline .value[data-metric=ttc]").startswith("ttc = ")
    assert (
        browser.evaluate(
            "getComputedStyle(document.querySelector('.timeline[data-metric=ttc] line.cursor'))"
            ".display"
        )
        != "none"
    )
    image = _shot(browser, "developer-view", tmp_path)
    assert _has_colour(image, "#d33f3f")  # the Failed verdict


def test_coverage_by_requirement_and_comparison(
    browser: Browser, base_url: str, tmp_path: Path
) -> None:
    browser.open(f"{base_url}coverage?run={SAMPLE_RUN}")
    assert "cut-in" in browser.evaluate(
        "[...document.querySelectorAll('#coverage tr[data-label]')].map(r => r.dataset.label)"
    )
    browser.click("a[data-by=requirement]")
    assert "by=requirement" in browser.evaluate("location.search")
    _shot(browser, "coverage", tmp_path)
    browser.open(f"{base_url}history/scenario?id=regress.xosc")
    runs = browser.evaluate(
        "[...document.querySelectorAll('#entries tbody tr a')].map(a => a.innerText)"
    )
    browser.open(f"{base_url}compare?base={runs[2]}&other={runs[0]}")
    regressed = browser.evaluate(
        "[...document.querySelectorAll('#changes tr[data-change=regressed]')]"
        ".map(r => r.cells[0].innerText)"
    )
    assert regressed == ["regress.xosc"]
    assert browser.text("[data-change=regressed]").startswith("1 regressed")
    _shot(browser, "compare", tmp_path)
