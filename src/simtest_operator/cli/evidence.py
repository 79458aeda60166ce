"""``simtest evidence``: export a campaign run's evidence bundle, and verify one offline."""

from __future__ import annotations

from pathlib import Path

import click

from simtest_operator.errors import SimtestError


@click.group()
def evidence() -> None:
    """Export a campaign run's evidence bundle (verdicts, metrics and content hashes of
    scenario, map, SUT, simulator and recording) and verify one offline."""


@evidence.command()
@click.argument("target", metavar="OUTDIR|DSN")
@click.option("--out", "out", required=True, type=click.Path(file_okay=False, path_type=Path),
              help="Folder to write the bundle to (new or empty).")  # fmt: skip
@click.option("--run", "run_key", metavar="KEY", help="Run key  [default: newest run]")
@click.option("--base-dir", type=click.Path(exists=True, file_okay=False, path_type=Path),
              help="Folder relative artifact paths start from  [default: OUTDIR]")  # fmt: skip
def export(target: str, out: Path, run_key: str | None, base_dir: Path | None) -> None:
    """Write the evidence bundle of one run of the results database at OUTDIR|DSN."""
    from simtest_operator.results import evidence as bundles
    from simtest_operator.results.querying import ReadOnlyDatabase

    base = base_dir or (Path(target) if Path(target).is_dir() else None)
    try:
        with ReadOnlyDatabase(target) as db:
            key = run_key or bundles.newest_run(db)
            exported = bundles.export(db, key, out, base_dir=base)
    except (SimtestError, OSError) as exc:
        click.echo(f"simtest evidence export: {exc}", err=True)
        raise SystemExit(2) from None
    click.echo(f"run {key}: {exported.scenarios} scenarios, {exported.files} files in {out}")
    for line in exported.missing:
        click.echo(f"  digest only: {line}")
    click.echo(f"manifest sha256 {exported.manifest_sha256}")


@evidence.command()
@click.argument("bundle", type=click.Path(exists=True, file_okay=False, path_type=Path))
def verify(bundle: Path) -> None:
    """Recompute every digest in BUNDLE and check it against the manifest and the digests
    recorded at run time; exit 1 on any difference."""
    from simtest_operator.results import evidence as bundles

    try:
        digest, problems = bundles.verify(bundle)
    except (SimtestError, OSError) as exc:
        click.echo(f"simtest evidence verify: {exc}", err=True)
        raise SystemExit(2) from None
    for problem in problems:
        click.echo(f"FAIL {problem}")
    if problems:
        click.echo(f"{bundle}: {len(problems)} problem(s); manifest sha256 {digest}")
        raise SystemExit(1)
    click.echo(f"{bundle}: verified; manifest sha256 {digest}")
