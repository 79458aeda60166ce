"""``simtest crds``: write the CRDs generated from the API models, or check for drift."""

from __future__ import annotations

from pathlib import Path

import click


@click.command()
@click.option(
    "--out",
    "out_dir",
    type=click.Path(path_type=Path),
    default=Path("crds"),
    show_default=True,
    help="Folder the CRD YAML files go to.",
)
@click.option("--check", is_flag=True, help="Exit 1 when the files differ from the models.")
def crds(out_dir: Path, check: bool) -> None:
    """Generate CustomResourceDefinitions from the pydantic models."""
    from simtest_operator.api import crdgen

    drift = crdgen.sync(out_dir, check=check)
    if check and drift:
        for name in drift:
            click.echo(f"drift: {out_dir / name} differs from the models; run `simtest crds`")
        raise SystemExit(1)
    click.echo(f"{'checked' if check else 'wrote'} {len(crdgen.CRD_FILES)} CRDs in {out_dir}")
