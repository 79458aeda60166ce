"""``simtest run`` with an external SUT: the example campaign's sidecar SUT is started as a local
process per scenario (there is no pod); the verdicts equal the in-process smoke campaign's and
every result names the SUT that produced it."""

from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner

from simtest_operator.cli.main import cli

REPO = Path(__file__).resolve().parents[2]


def verdicts(out: Path) -> dict[str, tuple[str, dict[str, str]]]:
    found = {}
    for path in sorted(out.glob("scenarios/*/result.json")):
        result = json.loads(path.read_text(encoding="utf-8"))
        found[result["scenarioId"]] = (result["verdict"], result["versions"])
    return found


def test_the_external_sut_campaign_runs_locally_like_the_in_process_one(tmp_path: Path) -> None:
    runs = {}
    for name in ("smoke", "external-sut"):
        manifest = REPO / "scenarios" / f"{name}-campaign.yaml"
        arguments = ["run", str(manifest), "-o", str(tmp_path / name), "-j", "1", "--plain"]
        result = CliRunner().invoke(cli, arguments)
        assert result.exit_code == 1, result.output  # one scenario fails, in both
        runs[name] = verdicts(tmp_path / name)
    inside, outside = runs["smoke"], runs["external-sut"]
    assert len(inside) == 6
    assert {k: v[0] for k, v in outside.items()} == {k: v[0] for k, v in inside.items()}
    for _, versions in outside.values():
        assert versions["sut.reported"] == "simtest-reference-sut 1.0.0"
        assert versions["sut.launch"] == "sidecar"
        assert versions["sut.image"] == "ghcr.io/simtest-dev/simtest-runner:0.1.0"
    assert all("sut.reported" not in versions for _, versions in inside.values())
