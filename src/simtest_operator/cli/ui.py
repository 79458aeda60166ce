"""``simtest ui``: serve the results UI from a results database until interrupted (waitress:
threads, idle connections closed, bounded headers; :mod:`simtest_operator.ui.server`)."""

from __future__ import annotations

from pathlib import Path

import click

from simtest_operator.errors import SimtestError
from simtest_operator.settings import Settings


@click.command()
@click.option("--database", "database", metavar="DSN|OUTDIR",
              help="PostgreSQL DSN, an output folder or a SQLite file; required unless "
              "SIMTEST_RESULTS_DATABASE names one.")  # fmt: skip
@click.option("--host", default="127.0.0.1", show_default=True,
              help="Address to listen on (0.0.0.0 in a pod).")  # fmt: skip
@click.option("--port", default=8080, show_default=True, type=click.IntRange(0, 65535),
              help="Port to listen on (0 picks a free one).")  # fmt: skip
@click.option("--artifacts", type=click.Path(exists=True, file_okay=False, path_type=Path),
              help="Folder relative artifact paths start from  [default: the output folder "
              "given as --database, else the current folder]")  # fmt: skip
def ui(database: str | None, host: str, port: int, artifacts: Path | None) -> None:
    """Serve the results UI from a results database (SQLite or PostgreSQL)."""
    database = database or Settings.from_env().results.database
    if database is None:
        raise click.MissingParameter(param_type="option", param_hint="'--database'")
    from simtest_operator import runner
    from simtest_operator.results import dsn
    from simtest_operator.results.querying import ReadOnlyDatabase
    from simtest_operator.ui import server, views

    located = dsn.classify(database)
    base = artifacts or (located if isinstance(located, Path) and located.is_dir() else None)
    try:
        db = ReadOnlyDatabase(database)
    except SimtestError as exc:
        click.echo(f"simtest ui: {exc}", err=True)
        raise SystemExit(2) from None
    context = views.Context(
        base_dir=base, read_trajectories=runner.read_recording, search=runner.search_section_of
    )
    try:
        httpd = server.Server(server.App(db, context), host=host, port=port)
    except OSError as exc:
        db.close()
        click.echo(f"simtest ui: cannot listen on {host}:{port}: {exc.strerror}", err=True)
        raise SystemExit(2) from None
    click.echo(f"simtest ui: serving {db.where} on http://{host}:{httpd.port}/", err=True)
    try:
        httpd.run()
    finally:
        httpd.close()
        db.close()
