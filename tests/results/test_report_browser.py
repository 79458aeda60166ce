"""The report as a person sees it: rendered by headless Chromium (Debian ``chromium``), offline.

Covers: after the page's script ran (``--dump-dom``), the overview tiles show the right counts,
the failing scenario's reason is on the page, opening ``#<scenario>`` expands its developer view
(the script works), which holds a trajectory SVG drawn from the real recording and the metric
timelines, and the comparison table lists the regression; the screenshot is a real rendering
(page size, the Failed and Passed colours of the tiles present). Name resolution is disabled, so
any attempt to load a remote resource would fail the rendering checks. The README's smoke
campaign run by ``simtest run`` on real SUMO: its header names SUMO and the installed version,
and the digest of the lock the environment was installed from (issue 17).
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import re
import shutil
import subprocess
from pathlib import Path

import lxml.html
import pytest
from PIL import Image

from simtest_operator import __version__
from simtest_operator.cli.main import cli
from tests.results.sampleoutdir import make_outdir

pytestmark = pytest.mark.browser

REPO = Path(__file__).resolve().parents[2]

FLAGS = (
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--host-resolver-rules=MAP * ~NOTFOUND",
)  # fmt: skip


def _chromium() -> str:
    found = shutil.which("chromium")
    if found is None:
        pytest.fail("headless Chromium not found; install it with: apt-get install -y chromium",
                    pytrace=False)  # fmt: skip
    return found


def _browse(url: str, profile: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [_chromium(), *FLAGS, f"--user-data-dir={profile}", *extra, url],
        capture_output=True, text=True, timeout=120, check=True,
    )  # fmt: skip


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from click.testing import CliRunner

    root = tmp_path_factory.mktemp("browser")
    now = make_outdir(root / "now")
    before = make_outdir(root / "before", previous=True)
    result = CliRunner().invoke(cli, ["report", str(now), "--compare", str(before)])
    assert result.exit_code == 0, result.output
    return now / "report.html"


def test_what_the_reader_sees(report: Path, tmp_path: Path) -> None:
    dom = _browse(f"{report.as_uri()}#s-cut-in-close-xosc", tmp_path / "profile", "--dump-dom")
    page = lxml.html.fromstring(dom.stdout)
    counts = {
        span.get("data-count"): span.text_content() for span in page.xpath("//span[@data-count]")
    }
    assert counts == {"Total": "8", "Passed": "3", "Failed": "1", "Timeout": "1", "Error": "0",
                      "Invalid": "1", "Skipped": "1", "Not run": "1"}  # fmt: skip
    assert page.get_element_by_id("shown-count").text_content() == "8"
    close = page.get_element_by_id("s-cut-in-close-xosc")
    assert close.get("open") is not None, "the script should open the scenario named in the URL"
    assert (
        close.xpath(".//p[@class='reason-full']")[0].text_content()
        == "collision with 'cutter' at t=7.2 s"
    )
    (plot,) = close.xpath(".//svg[@class='trajectories']")
    entities = [g.get("data-entity") for g in plot.xpath(".//g[@class='entity']")]
    assert sorted(entities) == ["ego", "object 1"]
    assert all(len(p.get("points").split()) > 50 for p in plot.xpath(".//polyline"))
    assert len(close.xpath(".//svg[@class='timeline']")) == 2
    closed = [
        d.get("id") for d in page.xpath("//details[@class='scenario']") if d.get("open") is None
    ]
    assert len(closed) == 7
    regressed = [
        row.xpath("./td")[0].text_content()
        for row in page.xpath("//table[@id='comparison-table']//tr[@data-change='regressed']")
    ]
    assert regressed == ["cut-in/close.xosc"]


def test_screenshot_is_a_real_rendering(report: Path, tmp_path: Path) -> None:
    shot = tmp_path / "report.png"
    _browse(
        report.as_uri(), tmp_path / "profile", f"--screenshot={shot}", "--window-size=1280,1600"
    )
    with Image.open(shot) as image:
        assert image.size == (1280, 1600)
        colours = image.convert("RGB").getcolors(maxcolors=1 << 20)
    assert colours is not None
    pixels = {colour: count for count, colour in colours}
    assert pixels.get((0xD3, 0x3F, 0x3F), 0) > 2000  # the red Failed tile and bar
    assert pixels.get((0x2E, 0x9D, 0x5B), 0) > 2000  # the green Passed tile and bar
    assert len(pixels) > 100  # text, charts and colours, not a blank page


@pytest.fixture(scope="module")
def smoke_report(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from click.testing import CliRunner

    root = tmp_path_factory.mktemp("smoke")
    result = CliRunner().invoke(
        cli,
        [
            "run",
            str(REPO / "scenarios" / "smoke-campaign.yaml"),
            "-o",
            str(root / "out"),
            "--plain",
        ],
        env={"SIMTEST_CACHE_DIR": str(root / "cache")},
    )
    assert result.exit_code == 1, result.output  # the README's deliberately close cut-in
    return root / "out" / "report.html"


def test_the_header_names_sumo_and_the_lock(smoke_report: Path, tmp_path: Path) -> None:
    dom = _browse(smoke_report.as_uri(), tmp_path / "profile", "--dump-dom")
    page = lxml.html.fromstring(dom.stdout)
    simulator = page.get_element_by_id("simulator").text_content()
    assert re.fullmatch(r"SUMO \d+\.\d+\.\d+ \(simtest engine \S+\)", simulator), simulator
    sumo = importlib.metadata.version("eclipse-sumo")
    assert simulator == f"SUMO {sumo} (simtest engine {__version__})"
    lock = page.get_element_by_id("lock")
    digest = hashlib.sha256((REPO / "uv.lock").read_bytes()).hexdigest()
    assert lock.get("title") == f"sha256:{digest}"  # the .venv beside it was synced from it
    assert lock.text_content() == f"sha256:{digest[:12]}"
