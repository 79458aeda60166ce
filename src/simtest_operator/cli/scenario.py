"""``simtest scenario run|check``: run one scenario, or every scenario under a directory.

Thin wiring: options -> :mod:`simtest_operator.runner.execution` -> formatted output.
"""

from __future__ import annotations

import os
from pathlib import Path

import click
from rich.console import Console
from rich.table import Table

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import FileKind, file_kind
from simtest_operator.runner import execution
from simtest_operator.settings import Settings
from simtest_operator.sim import SutConfig, Takeover


def _sut(takeover: str) -> SutConfig:
    return SutConfig(takeover=Takeover(takeover))


@click.group("scenario")
def scenario() -> None:
    """Run OpenSCENARIO files on the SUMO-backed simulator stand-in."""


@scenario.command("run")
@click.argument("file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option(
    "--out",
    "out",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Directory for recording.mcap, run.log and result.json.",
)
@click.option("--no-record", is_flag=True, help="Do not write the omega-prime recording.")
@click.option(
    "--takeover",
    type=click.Choice([t.value for t in Takeover]),
    default=Takeover.ON_CONTROLLER.value,
    show_default=True,
    help="When the SUT driver model takes the ego over.",
)
def run(file: Path, out: Path | None, no_record: bool, takeover: str) -> None:
    """Run FILE and print its verdict, reason and metrics."""
    settings = Settings.from_env()
    report = execution.run_scenario(
        execution.RunRequest(
            scenario=file,
            nets_dir=settings.cache.nets,
            sut=_sut(takeover),
            simulation=settings.simulation,
            output_dir=out,
            record=not no_record,
        )
    )
    outcome = report.outcome
    click.echo(f"verdict: {outcome.verdict}")
    click.echo(f"reason: {outcome.reason}")
    for key, value in sorted(outcome.metrics.items()):
        click.echo(f"{key}: {value:g}")
    if outcome.ignored_elements:
        click.echo(f"ignored: {', '.join(outcome.ignored_elements)}")
    for name, uri in sorted(outcome.artifacts.items()):
        click.echo(f"{name}: {uri}")
    raise SystemExit(0 if outcome.verdict.counts_as_ran else 1)


def _scenario_files(directory: Path) -> list[Path]:
    files = []
    for path in sorted(directory.rglob("*.xosc")):
        try:
            if file_kind(path) is FileKind.CATALOG:
                continue
        except ScenarioError:
            pass  # unreadable files are still listed; their run says why
        files.append(path)
    return files


@scenario.command("check")
@click.argument("directory", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option(
    "--jobs",
    "-j",
    type=click.IntRange(min=1),
    default=None,
    help="Worker processes (default: CPU count).",
)
@click.option(
    "--reference",
    type=click.Path(exists=True, dir_okay=False, path_type=Path),
    default=None,
    help="esmini-reference.json to compare end times and paths with.",
)
@click.option(
    "--takeover",
    type=click.Choice([t.value for t in Takeover]),
    default=Takeover.ON_CONTROLLER.value,
    show_default=True,
    help="When the SUT driver model takes the ego over.",
)
def check(directory: Path, jobs: int | None, reference: Path | None, takeover: str) -> None:
    """Run every scenario under DIRECTORY in parallel and print a table."""
    settings = Settings.from_env()
    files = _scenario_files(directory)
    requests = [
        execution.RunRequest(
            scenario=path,
            scenario_id=str(path.relative_to(directory)),
            nets_dir=settings.cache.nets,
            sut=_sut(takeover),
            simulation=settings.simulation,
            record=False,
        )
        for path in files
    ]
    reports: list[execution.RunReport | None] = [None] * len(requests)
    for index, report in execution.run_many(requests, jobs=jobs or os.cpu_count() or 1):
        reports[index] = report
    table = Table(title=f"scenarios under {directory}")
    for column in ("file", "verdict", "reason", "simulated s", "wall s"):
        table.add_column(column, overflow="fold")
    ran = invalid = errors = 0
    for maybe in reports:
        assert maybe is not None
        outcome = maybe.outcome
        ran += outcome.verdict.counts_as_ran
        invalid += outcome.verdict.value == "Invalid"
        errors += outcome.verdict.value == "Error"
        table.add_row(
            outcome.scenario_id,
            outcome.verdict.value,
            outcome.reason,
            f"{outcome.simulated_seconds:.2f}",
            f"{outcome.wall_seconds:.2f}",
        )
    console = Console(width=max(Console().width, 160))
    console.print(table)
    click.echo(f"{ran} ran, {invalid} invalid, {errors} errors")
