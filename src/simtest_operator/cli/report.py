"""``simtest report``: the HTML report (and optionally JUnit XML) of a run's output folder.

Parses options, hands the runner's recording reader to the results package (the two sit on the
same layer and do not import each other) and prints what :func:`results.publishing.publish`
returns.
"""

from __future__ import annotations

import datetime
import socket
from pathlib import Path

import click

from simtest_operator import runner
from simtest_operator.errors import SimtestError
from simtest_operator.settings import Settings


@click.command()
@click.argument("outdir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option(
    "--compare",
    "compare",
    metavar="OTHER_OUTDIR|DSN",
    help="Compare with the newest run in another output folder (or database).",
)
@click.option(
    "--out",
    "out",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Report file to write  [default: OUTDIR/report.html]",
)
@click.option(
    "--junit",
    "junit",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Also write JUnit XML for CI to this file.",
)
@click.option(
    "--database",
    metavar="DSN",
    help="Read the run from this PostgreSQL database instead of OUTDIR/results.sqlite "
    "(env SIMTEST_RESULTS_DATABASE).",
)
@click.option("--run", "run_key", metavar="KEY", help="Run key to report  [default: newest run]")
@click.option("--compare-run", metavar="KEY", help="Run key in the comparison store.")
def report(
    outdir: Path,
    compare: str | None,
    out: Path | None,
    junit: Path | None,
    database: str | None,
    run_key: str | None,
    compare_run: str | None,
) -> None:
    """Write a self-contained HTML report of the run in OUTDIR (overview, coverage, per-scenario
    detail with trajectories, and a comparison with another run)."""
    from simtest_operator.results import dsn, publishing, records

    target: str | Path = database or Settings.from_env().results.database or outdir
    other = None
    if compare is not None or compare_run is not None:
        compare_target: str | Path = compare if compare is not None else target
        other = publishing.RunRef(
            target=compare_target,
            run_key=records.RunKey(compare_run) if compare_run else None,
        )
    try:
        published = publishing.publish(
            publishing.RunRef(
                target=target,
                run_key=records.RunKey(run_key) if run_key else None,
                base_dir=outdir,
            ),
            now=datetime.datetime.now(datetime.UTC),
            report_path=out or outdir / publishing.REPORT_FILENAME,
            junit_path=junit,
            compare_with=other,
            read_trajectories=runner.read_recording,
            hostname=socket.gethostname(),
            search=runner.search_section_of,
        )
    except SimtestError as exc:
        click.echo(f"simtest report: {exc}", err=True)
        raise SystemExit(2) from None
    counts = ", ".join(f"{n} {v.lower()}" for v, n in published.totals.items() if n)
    click.echo(f"run {published.run_key} ({dsn.describe(target)}): {counts}")
    if published.comparison is not None:
        moved = ", ".join(f"{n} {c.value}" for c, n in published.comparison.items() if n)
        against = dsn.describe(compare) if compare is not None else compare_run
        click.echo(f"compared with {against}: {moved or 'no scenarios'}")
    if published.report is not None:
        click.echo(f"report: {published.report}")
    if published.junit is not None:
        click.echo(f"junit: {published.junit}")
