"""``simtest scenario run|check|nets``: run one scenario, or every scenario under a directory;
ship the converted road networks of the maps under a directory.

Thin wiring: options -> :func:`simtest_operator.runner.run_scenario` -> formatted output.
``check`` expands ParameterValueDistribution files into their concrete runs and skips catalogs.
``run`` exits like ``simtest run`` over a one-scenario list
(:func:`simtest_operator.runner.summarise`), so a script or CI step can use either command with
the same meaning of 0, 1 and 2.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import click

from simtest_operator import runner
from simtest_operator.cli import options
from simtest_operator.cli.options import F
from simtest_operator.cli.terminal import markup, printable
from simtest_operator.errors import ScenarioError, SimulationError
from simtest_operator.evaluation import reference as references
from simtest_operator.openscenario import (
    Deviation,
    FileKind,
    LoadOptions,
    expand_distribution,
    file_kind,
)
from simtest_operator.openscenario.confinement import default_root
from simtest_operator.openscenario.loading import MAX_SCENARIO_BYTES
from simtest_operator.settings import Settings
from simtest_operator.sim import SutConfig, Takeover
from simtest_operator.verdicts import Verdict

_TAKEOVER = click.option(
    "--takeover",
    type=click.Choice([t.value for t in Takeover]),
    default=Takeover.ON_CONTROLLER.value,
    show_default=True,
    help="When the SUT driver model takes the ego over.",
)


_STRICT = click.option(
    "--strict",
    is_flag=True,
    help="Refuse deviations from the OpenSCENARIO schema that players accept (parameterType "
    "'int', a heading in degrees, ...): the scenario is Invalid instead of running with a warning.",
)


_MAPS = click.option(
    "--maps",
    "maps",
    multiple=True,
    type=click.Path(exists=True, file_okay=False, path_type=Path),
    help='A map library: folder of <name>.xodr files that <LogicFile filepath="<name>"/> '
    "names (repeatable; searched before SIMTEST_MAP_PATH and the shipped CARLA towns).",
)


_MAX_SIZE = click.option(
    "--max-scenario-mb",
    "max_mb",
    type=click.FloatRange(min=0.001),
    default=MAX_SCENARIO_BYTES / 2**20,
    show_default=True,
    help="Size limit of scenario and catalog files (loading takes ~20x in memory).",
)


def _root(default: str) -> Callable[[F], F]:
    """``--root``: the folder the files a scenario references must be inside."""
    return click.option(
        "--root",
        type=click.Path(exists=True, file_okay=False, path_type=Path),
        default=None,
        help="Source root: files a scenario references (road network, catalogs) must be inside "
        f"it [default: {default}].",
    )


_LOADING = options.stack(_TAKEOVER, _STRICT, _MAPS, _MAX_SIZE)
"""How a scenario is loaded and driven: what ``scenario run`` and ``scenario check`` share."""


def _loading(
    settings: Settings, strict: bool, root: Path | None, maps: tuple[Path, ...], max_mb: float
) -> LoadOptions:
    return LoadOptions(
        strict=strict,
        source_root=root,
        maps=(*maps, *settings.maps),
        max_bytes=int(max_mb * 2**20),
    )


def _short(deviation: Deviation) -> str:
    line = deviation.line if deviation.line is not None else "?"
    return f"line {line}: {deviation.message} [{deviation.code}]"


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
@_LOADING
@_root("the enclosing git work tree, else FILE's folder")
def run(
    file: Path,
    out: Path | None,
    no_record: bool,
    takeover: str,
    strict: bool,
    maps: tuple[Path, ...],
    root: Path | None,
    max_mb: float,
) -> None:
    """Run FILE and print its verdict, reason, rule set, accepted deviations and metrics.

    Exit code, as for `simtest run`: 0 passed, 1 failed or timed out (verdict Failed or
    Timeout: a verdict on the system under test), 2 error or invalid input (Error, Invalid,
    Skipped: the scenario could not be judged). Accepted deviations from the schema do not change
    the exit code unless --strict makes them Invalid.
    """
    settings = Settings.from_env()
    report = runner.run_scenario(
        runner.RunRequest(
            scenario=file,
            nets_dir=settings.cache.nets,
            sut=SutConfig(takeover=Takeover(takeover)),
            simulation=settings.simulation,
            output_dir=out,
            record=not no_record,
            loading=_loading(settings, strict, root or default_root(file), maps, max_mb),
        )
    )
    outcome = report.outcome
    click.echo(f"verdict: {outcome.verdict}")
    click.echo(f"reason: {printable(outcome.reason)}")
    if report.rules:
        click.echo(f"rules: {report.rules}")
    if "outside the scenario's source root" in outcome.reason:
        click.echo("hint: --root DIR lets the scenario reference files anywhere inside DIR")
    for deviation in report.deviations:
        click.echo(f"warning: {printable(deviation.describe())}")
    for key, value in sorted(outcome.metrics.items()):
        click.echo(f"{key}: {value:g}")
    if outcome.ignored_elements:
        click.echo(f"ignored: {printable(', '.join(outcome.ignored_elements))}")
    for name, uri in sorted(outcome.artifacts.items()):
        click.echo(f"{name}: {printable(uri)}")
    raise SystemExit(
        runner.summarise([outcome.scenario_id], {outcome.scenario_id: outcome}).exit_code
    )


def _requests(
    directory: Path, settings: Settings, sut: SutConfig, loading: LoadOptions
) -> list[runner.RunRequest]:
    requests = []
    for path in sorted(directory.rglob("*.xosc")):
        overrides_list: list[tuple[str, Path, Mapping[str, str]]]
        scenario_id = path.relative_to(directory).as_posix()
        try:
            kind = file_kind(path)
        except ScenarioError:
            kind = FileKind.SCENARIO  # unreadable: its run says why
        if kind is FileKind.CATALOG:
            continue
        if kind is FileKind.DISTRIBUTION:
            try:
                runs = expand_distribution(path, seed=settings.simulation.seed)
            except ScenarioError:
                runs = []
            if runs:
                prefix = scenario_id.rsplit("/", 1)[0] + "/" if "/" in scenario_id else ""
                overrides_list = [(prefix + r.id, r.scenario, r.overrides) for r in runs]
            else:
                overrides_list = [(scenario_id, path, {})]
        else:
            overrides_list = [(scenario_id, path, {})]
        for run_id, scenario_path, overrides in overrides_list:
            requests.append(
                runner.RunRequest(
                    scenario=scenario_path,
                    scenario_id=run_id,
                    overrides=dict(overrides),
                    nets_dir=settings.cache.nets,
                    sut=sut,
                    simulation=settings.simulation,
                    record=False,
                    loading=loading,
                )
            )
    return requests


def _comparison(
    reference: Mapping[str, Any],
    request: runner.RunRequest,
    report: runner.RunReport,
) -> references.Comparison | None:
    if request.overrides or not report.outcome.verdict.counts_as_ran:
        return None
    key = references.find(reference, request.scenario)
    if key is None:
        return None
    end = report.outcome.simulated_seconds if report.storyboard_complete else None
    return references.compare(
        key,
        reference[key],
        samples=report.samples,
        end_time=end,
        intended=report.intended,
        time_limit=request.criteria.time_limit,
    )


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
@_LOADING
@_root("DIRECTORY")
def check(
    directory: Path,
    jobs: int | None,
    reference: Path | None,
    takeover: str,
    strict: bool,
    maps: tuple[Path, ...],
    root: Path | None,
    max_mb: float,
) -> None:
    """Run every scenario under DIRECTORY in parallel and print a table with each verdict, the
    rule set it ran under and the schema deviations accepted in the file (warnings). Files the
    scenarios reference must be inside DIRECTORY (or --root) or come from a map library."""
    # Only `check` prints a table: `scenario run` starts without rich.
    from rich.console import Console
    from rich.table import Table

    settings = Settings.from_env()
    loading = _loading(settings, strict, root or directory, maps, max_mb)
    requests = _requests(directory, settings, SutConfig(takeover=Takeover(takeover)), loading)
    ref = references.load(reference) if reference is not None else None
    reports: dict[int, runner.RunReport] = {}
    for index, report in runner.run_many(requests, jobs=jobs or os.cpu_count() or 1):
        reports[index] = report
    table = Table(title=f"scenarios under {markup(directory)}")
    columns = ["file", "verdict", "rules", "reason", "warnings", "simulated s", "wall s"]
    if ref is not None:
        columns += ["end Δ s", "median err m", "max err m", "match", "intended differences"]
    for column in columns:
        table.add_column(column, overflow="fold")
    counts = dict.fromkeys(Verdict, 0)
    compared = matched = 0
    for index, request in enumerate(requests):
        outcome = reports[index].outcome
        counts[outcome.verdict] += 1
        row = [  # user text escaped cell by cell: the warnings cell keeps its line breaks
            markup(outcome.scenario_id),
            outcome.verdict.value,
            reports[index].rules,
            markup(outcome.reason),
            "\n".join(markup(_short(d)) for d in reports[index].deviations),
            f"{outcome.simulated_seconds:.2f}",
            f"{outcome.wall_seconds:.2f}",
        ]
        if ref is not None:
            comparison = _comparison(ref, request, reports[index])
            if comparison is None:
                row += ["", "", "", "", ""]
            else:
                compared += 1
                matched += comparison.match
                end = comparison.end_difference
                row += [
                    f"{end:+.2f}" if end is not None else "no end",
                    f"{comparison.worst_median:.2f}",
                    f"{max((e.maximum for e in comparison.entities), default=0.0):.2f}",
                    "yes" if comparison.match else "no",
                    markup("; ".join(comparison.intended)),
                ]
        table.add_row(*row)
    Console(width=max(Console().width, 200 if ref is not None else 160)).print(table)
    if ref is not None:
        click.echo(f"{matched} of {compared} compared scenarios match the reference")
    ran = sum(counts[v] for v in Verdict if v.counts_as_ran)
    warned = sum(1 for report in reports.values() if report.deviations)
    click.echo(f"{ran} ran, {counts[Verdict.INVALID]} invalid, {counts[Verdict.ERROR]} errors")
    if warned:
        click.echo(f"{warned} scenarios accepted with deviations from the schema (see warnings)")


@scenario.command("nets")
@click.argument("directory", type=click.Path(exists=True, file_okay=False, path_type=Path))
def nets(directory: Path) -> None:
    """Convert every OpenDRIVE map under DIRECTORY into the SUMO network the simulator loads,
    kept in a .simtest-nets folder beside the map.

    Simulator pods then load the network from the scenario volume instead of running netconvert
    each (their own cache dies with the pod). Run it where the scenarios are staged, with the
    same simtest release as the runner image: a network made by another SUMO version, or for a
    changed map, is not used, and that map is converted in every pod as before.
    """
    from simtest_operator.sim import netcache

    maps = sorted(
        path
        for path in directory.rglob("*.xodr")
        if path.is_file() and netcache.SHIPPED_DIR not in path.parts
    )
    converted = failed = 0
    for path in maps:
        try:
            shipped = netcache.ship_net(path)
        except (ScenarioError, SimulationError) as exc:
            failed += 1
            click.echo(f"not converted: {printable(str(path))}: {printable(str(exc))}", err=True)
            continue
        converted += not shipped.from_cache
        state = "shipped already" if shipped.from_cache else f"converted in {shipped.seconds:.2f} s"
        click.echo(f"{printable(str(path))}: {state}")
    click.echo(
        f"{len(maps)} maps: {converted} converted, {len(maps) - converted - failed} "
        f"shipped already, {failed} not convertible (pods try netconvert again, as before)"
    )
