"""``simtest run MANIFEST``: a whole TestCampaign on this machine, with the operator's artifacts.

Wiring only: options become a :class:`~simtest_operator.runner.LocalRunRequest`, the
runner does the work, and this module shows progress (a rich progress bar on a terminal, one plain
line per scenario otherwise), prints the summary and exits 0 (all passed), 1 (some failed) or
2 (errors, invalid input, interrupted) with a one-line reason.

Every piece of user text (paths, campaign and scenario names, reasons, YAML error messages) goes
through :mod:`~simtest_operator.cli.terminal` (markup escaped, control characters written as
``\\x1b``): a scenario called ``[/x]`` once crashed the CLI with a MarkupError and exit 1, which CI
reads as "the SUT failed" (issue 12), and an ESC in a file name reached the terminal (issue 29).

The first Ctrl-C, SIGTERM (CI cancelling a job, ``timeout``, ``docker stop``) or SIGHUP (a closed
terminal or SSH session) stops the run in order (workers killed, unfinished scenarios marked as
not run, the campaign ``interrupted``, report written, exit 2; the same command resumes). Further
SIGTERMs and SIGHUPs do not cut that short (a CI runner may send several); only a second Ctrl-C,
from a person, aborts at once -- still exit 2, never 1 ("the SUT failed").
"""

from __future__ import annotations

import contextlib
import datetime
import os
import re
import signal
import threading
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from types import FrameType
from typing import Literal, NoReturn

import click
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from simtest_operator import runner
from simtest_operator.cli.terminal import markup, printable
from simtest_operator.errors import ScenarioError, SimtestError, SourceError
from simtest_operator.scenarios.specs import SecretRef
from simtest_operator.settings import SECRET_PREFIX, Settings
from simtest_operator.verdicts import Verdict

LISTED = 20
"""Non-passed scenarios listed by name in the summary."""
_COLOURS = {
    Verdict.PASSED: "green",
    Verdict.FAILED: "red",
    Verdict.TIMEOUT: "red",
    Verdict.ERROR: "magenta",
    Verdict.INVALID: "magenta",
    Verdict.SKIPPED: "yellow",
}


def secret_variable(ref: SecretRef) -> str:
    """The environment variable that holds Secret key ``ref`` for local runs."""
    return SECRET_PREFIX + re.sub(r"[^A-Z0-9]", "_", f"{ref.name}_{ref.key}".upper())


def env_secrets(env: Mapping[str, str]) -> Callable[[SecretRef], str]:
    """A secret provider reading ``SIMTEST_SECRET_<NAME>_<KEY>`` variables."""

    def provide(ref: SecretRef) -> str:
        value = env.get(secret_variable(ref))
        if not value:
            raise SourceError(
                f"Secret {ref.name}/{ref.key} is not available locally; set {secret_variable(ref)}"
            )
        return value

    return provide


@click.command("run")
@click.argument("manifest", required=False, type=click.Path(path_type=Path, dir_okay=False))
@click.option(
    "-o",
    "--output",
    type=click.Path(path_type=Path, file_okay=False),
    help="Output folder; an existing one of the same campaign is resumed. "
    "Default: simtest-runs/<campaign>-<UTC time>.",
)
@click.option(
    "-j",
    "--parallel",
    type=click.IntRange(min=1),
    help="Worker processes (default: all cores, at most spec.execution.maxParallel).",
)
@click.option(
    "--frozen",
    type=click.Path(path_type=Path, dir_okay=False, exists=True),
    help="Run exactly this frozen list (a frozen.json) instead of resolving sources.",
)
@click.option(
    "--rerun-failed",
    type=click.Path(path_type=Path, file_okay=False, exists=True),
    help="Run the scenarios of an earlier output folder that did not pass.",
)
@click.option(
    "--db",
    "database",
    help="Results store: a PostgreSQL DSN or a SQLite file (default: in the output).",
)
@click.option("--plain", is_flag=True, help="Plain progress lines even on a terminal.")
@click.option(
    "--engine",
    type=click.Choice(["sumo", "fake"]),
    default="sumo",
    hidden=True,
    help="'fake' runs the documented test double (runner.fakes), for tests only.",
)
def run(
    manifest: Path | None,
    output: Path | None,
    parallel: int | None,
    frozen: Path | None,
    rerun_failed: Path | None,
    database: str | None,
    plain: bool,
    engine: Literal["sumo", "fake"],
) -> None:
    """Run a TestCampaign MANIFEST on this machine, in parallel worker processes.

    Writes per scenario a recording, a log and a result JSON, plus frozen.json, a results
    database, junit.xml and report.html into the output folder. Exit code: 0 all passed,
    1 some failed, 2 errors or invalid input.
    """
    console = Console(highlight=False)
    errors = Console(stderr=True, highlight=False)
    if manifest is None and rerun_failed is None:
        _fail(errors, "give a MANIFEST (or --rerun-failed OUTDIR)")
    if frozen is not None and rerun_failed is not None:
        _fail(errors, "--frozen and --rerun-failed exclude each other")
    settings = Settings.from_env()
    request = runner.LocalRunRequest(
        manifest=manifest,
        output=output or _default_output(manifest, rerun_failed),
        settings=settings,
        execute=runner.engine(engine),
        parallel=parallel,
        frozen=frozen,
        rerun_failed=rerun_failed,
        database=database,
        secrets=env_secrets(settings.secrets),
        cpu_count=len(os.sched_getaffinity(0)),
    )
    live = console.is_terminal and not plain
    view = _Live(console) if live else _Plain(console)
    stop = threading.Event()
    try:
        # The handlers stay until the summary is printed: a signal arriving just after the
        # clean stop must not take the default action (killed, or "Aborted!" with exit 1).
        with _graceful_interrupt(stop, errors):
            with view:
                result = runner.run_campaign(request, on_event=view.event, stop=stop)
            _print_summary(console, result)
    except KeyboardInterrupt:
        _fail(errors, "aborted by a second Ctrl-C; the same command resumes the campaign")
    except ScenarioError as exc:
        _fail(errors, str(exc))
    except SimtestError as exc:
        _fail(errors, f"{type(exc).__name__}: {exc}")
    raise SystemExit(result.summary.exit_code)


def _default_output(manifest: Path | None, rerun_failed: Path | None) -> Path:
    stamp = datetime.datetime.now(datetime.UTC).strftime("%Y%m%dT%H%M%SZ")
    stem = manifest.stem if manifest is not None else f"rerun-{(rerun_failed or Path()).name}"
    return Path("simtest-runs") / f"{stem}-{stamp}"


def _fail(errors: Console, reason: str) -> NoReturn:
    errors.print(f"[bold red]error:[/] {markup(reason)}", soft_wrap=True)
    raise SystemExit(runner.EXIT_ERROR)


_STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


@contextlib.contextmanager
def _graceful_interrupt(stop: threading.Event, errors: Console) -> Iterator[None]:
    # SIGTERM's default action killed the process mid-run: campaign.json stayed "running" and no
    # report was written (issue 12); a second SIGTERM 50 ms later then aborted with exit 1, and
    # SIGHUP still killed it (issue 29). All three now take the same orderly path.
    def handler(signum: int, frame: FrameType | None) -> None:
        name = signal.Signals(signum).name
        if stop.is_set():
            if signum == signal.SIGINT:
                raise KeyboardInterrupt
            _tell(errors, f"{name} again: already stopping (Ctrl-C to abort at once)")
            return
        stop.set()
        _tell(
            errors,
            f"stopping ({name}): killing workers, marking unfinished scenarios as not run "
            "(Ctrl-C again to abort at once)",
        )

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {number: signal.signal(number, handler) for number in _STOP_SIGNALS}
    try:
        yield
    finally:
        for number, action in previous.items():
            signal.signal(number, action)


def _tell(errors: Console, message: str) -> None:
    # After a SIGHUP the terminal may be gone: a failed write must not become an exception
    # raised wherever the signal interrupted the run.
    with contextlib.suppress(OSError):
        errors.print(message, markup=False)


class _Counts:
    def __init__(self) -> None:
        self.done = 0
        self.by_verdict: dict[Verdict, int] = dict.fromkeys(Verdict, 0)

    def add(self, verdict: Verdict) -> None:
        self.done += 1
        self.by_verdict[verdict] += 1

    def line(self) -> str:
        v = self.by_verdict
        errored = v[Verdict.ERROR] + v[Verdict.INVALID]
        return (
            f"[green]{v[Verdict.PASSED]} passed[/] [red]{v[Verdict.FAILED] + v[Verdict.TIMEOUT]}"
            f" failed[/] [magenta]{errored} errored[/]"
        )


class _Plain:
    """One line per event, for logs and CI."""

    def __init__(self, console: Console) -> None:
        self.console = console
        self.counts = _Counts()
        self.total = 0

    def __enter__(self) -> _Plain:
        return self

    def __exit__(self, *exc: object) -> None:
        return None

    def event(self, event: runner.CampaignEvent) -> None:
        if isinstance(event, runner.Prepared):
            _print_prepared(self.console, event)
            self.total = event.total
            self.counts.done = event.finished
        elif isinstance(event, runner.Retrying):
            o = event.outcome
            self.console.print(
                f"retry   {printable(o.scenario_id)} after attempt {o.attempts}: "
                f"{printable(o.reason)}",
                markup=False,
                soft_wrap=True,
            )
        elif isinstance(event, runner.Finished):
            o = event.outcome
            self.counts.add(o.verdict)
            width = len(str(self.total))
            reason = (
                f"  {printable(o.reason)}" if o.reason and o.verdict is not Verdict.PASSED else ""
            )
            self.console.print(
                f"[{self.counts.done:>{width}}/{self.total}] {o.verdict.value:<8} "
                f"{printable(o.scenario_id)} ({o.wall_seconds:.1f} s){reason}",
                markup=False,
                soft_wrap=True,
            )


class _Live(_Plain):
    """A rich progress bar with verdict counts and ETA; problems are printed above it."""

    def __init__(self, console: Console) -> None:
        super().__init__(console)
        self.progress = Progress(
            TextColumn("[bold]{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[counts]}"),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            console=console,
            transient=False,
        )
        self.task = self.progress.add_task("scenarios", total=None, counts="")

    def __enter__(self) -> _Live:
        self.progress.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.progress.stop()

    def event(self, event: runner.CampaignEvent) -> None:
        if isinstance(event, runner.Prepared):
            _print_prepared(self.console, event)
            self.total = event.total
            self.progress.update(
                self.task,
                total=event.total,
                completed=event.finished,
                description=markup(event.campaign),
                counts=self.counts.line(),
            )
        elif isinstance(event, runner.Retrying):
            o = event.outcome
            self.console.print(
                f"[yellow]retry[/] {markup(o.scenario_id)} after attempt {o.attempts}: "
                f"{markup(o.reason)}",
                soft_wrap=True,
            )
        elif isinstance(event, runner.Finished):
            o = event.outcome
            self.counts.add(o.verdict)
            if o.verdict is not Verdict.PASSED:
                colour = _COLOURS[o.verdict]
                self.console.print(
                    f"[{colour}]{o.verdict.value:<8}[/] {markup(o.scenario_id)}  "
                    f"{markup(o.reason)}",
                    soft_wrap=True,
                )
            self.progress.update(self.task, advance=1, counts=self.counts.line())


def _print_prepared(console: Console, event: runner.Prepared) -> None:
    verb = "resuming" if event.resumed else "running"
    todo = event.total - event.finished
    console.print(
        f"{verb} campaign [bold]{markup(event.campaign)}[/]: {todo} of {event.total} scenarios "
        f"on {event.parallel} worker process(es)\n  output  {markup(str(event.output))}\n"
        f"  results {markup(event.store)}",
        soft_wrap=True,
    )
    for note in event.notes:
        console.print(f"  note    {printable(note)}", markup=False, soft_wrap=True)


def _print_summary(console: Console, result: runner.LocalRunResult) -> None:
    summary = result.summary
    table = Table(title=f"{summary.total} scenarios", show_edge=False)
    for verdict in Verdict:
        table.add_column(verdict.value, justify="right", style=_COLOURS[verdict])
    table.add_row(*(str(summary.counts.get(v, 0)) for v in Verdict))
    console.print(table)
    problems = [(o.scenario_id, o.verdict, o.reason) for o in result.not_passed]
    if problems:
        listing = Table(show_edge=False, title="not passed")
        for column in ("scenario", "verdict", "reason"):
            listing.add_column(column, overflow="fold")
        for ident, verdict, reason in problems[:LISTED]:
            listing.add_row(
                markup(ident), f"[{_COLOURS[verdict]}]{verdict.value}[/]", markup(reason)
            )
        console.print(listing)
        if len(problems) > LISTED:
            console.print(
                f"... and {len(problems) - LISTED} more (see {printable(result.output)})",
                markup=False,
            )
    if result.search is not None:
        console.print("[bold]search[/]")
        for line in runner.search_lines(result.search.search):
            console.print(f"  {printable(line)}", markup=False, soft_wrap=True)
        console.print(f"  summary {printable(result.search.path)}", markup=False, soft_wrap=True)
    for warning in result.warnings:
        console.print(f"[yellow]warning:[/] {markup(warning)}", soft_wrap=True)
    console.print(f"wall time {result.wall_seconds:.1f} s on {result.parallel} worker(s)")
    for label, path in (
        ("output", result.output),
        ("report", result.report),
        ("junit", result.junit),
    ):
        if path is not None:
            console.print(f"{label:<7}{printable(path)}", markup=False, soft_wrap=True)
    colour = {0: "green", 1: "red"}.get(summary.exit_code, "magenta")
    console.print(f"[bold {colour}]{markup(summary.reason)}[/]", soft_wrap=True)
