"""``simtest search``: what a finished search found, as files.

``simtest search export`` writes the most critical concrete scenarios of a search (``simtest
run`` or a cluster campaign with ``spec.search``) as ``.xosc`` files for a regression suite: the
logical scenario, fetched as it was pinned, with its parameter values replaced.
"""

from __future__ import annotations

from pathlib import Path

import click

from simtest_operator.errors import SimtestError
from simtest_operator.settings import Settings


@click.group()
def search() -> None:
    """What a finished search found: export its critical concrete scenarios."""


@search.command()
@click.argument("results", metavar="OUTDIR|DSN")
@click.option("--out", "out", required=True, type=click.Path(file_okay=False, path_type=Path),
              help="Folder to write the .xosc files to (created when missing).")  # fmt: skip
@click.option("--top", default=10, show_default=True, type=click.IntRange(1, 1000),
              help="How many of the most critical concrete scenarios.")  # fmt: skip
@click.option("--run", "run_key", metavar="KEY", help="Run key  [default: newest run]")
def export(results: str, out: Path, top: int, run_key: str | None) -> None:
    """Write the TOP most critical concrete scenarios of the search in OUTDIR (an output
    folder of ``simtest run``) or a results database (DSN) as .xosc files."""
    from simtest_operator import runner
    from simtest_operator.scenarios.resolving import FetchContext

    target: str | Path = Path(results) if Path(results).is_dir() else results
    fetch = FetchContext(base_dir=Path.cwd(), cache_dir=Settings.from_env().cache.sources)
    try:
        written = runner.export_search(target, out, fetch=fetch, top=top, run_key=run_key)
    except SimtestError as exc:
        click.echo(f"simtest search export: {exc}", err=True)
        raise SystemExit(2) from None
    for path in written:
        click.echo(str(path))
    click.echo(f"{len(written)} concrete scenario(s) in {out}", err=True)
