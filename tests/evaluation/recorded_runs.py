"""Real recorded runs for the re-evaluation tests: a campaign of library scenarios on the SUMO
stand-in (``simtest run``), whose base scenarios are known by construction of the templates."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from click.testing import CliRunner

from simtest_operator.cli.main import cli

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
LIBRARY = SCENARIOS / "library"


def write_manifest(
    folder: Path,
    *,
    name: str,
    source: Path,
    include: Sequence[str],
    sut_version: str = "1.0.0",
    time_headway: float = 1.5,
) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    patterns = ", ".join(f'"{p}"' for p in include)
    manifest = folder / f"{name}.yaml"
    manifest.write_text(
        f"""apiVersion: simtest.dev/v1alpha1
kind: TestCampaign
metadata:
  name: {name}
spec:
  scenarios:
    sources:
      - path: {source}
    include: [{patterns}]
  environment:
    sut:
      name: idm-driver
      version: "{sut_version}"
      driverModel:
        timeHeadway: {time_headway}
    simulator:
      stepLength: 0.05
      seed: 42
      record: true
  execution:
    timeoutSeconds: 60
  evaluation:
    criteria:
      collision: Forbidden
""",
        encoding="utf-8",
    )
    return manifest


def run_campaign(manifest: Path, out: Path, *extra: str) -> Path:
    """Run the campaign with one worker; any verdict is fine, a crash is not."""
    args = ["run", str(manifest), "-o", str(out), "-j", "1", "--plain", *extra]
    result = CliRunner().invoke(cli, args)
    assert result.exit_code in (0, 1), result.output
    return out


def sample(category: str, count: int = 3) -> list[str]:
    """``count`` scenarios of a library category, spread over its parameter grid."""
    files = sorted(p.name for p in (LIBRARY / category).glob("*.xosc"))
    step = max(1, len(files) // count)
    return [f"{category}/{name}" for name in files[::step][:count]]
