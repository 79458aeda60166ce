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
@click.option(
    "--docs",
    "docs_dir",
    type=click.Path(path_type=Path),
    default=Path("docs"),
    show_default=True,
    help="Folder the generated CRD reference goes to.",
)
@click.option("--check", is_flag=True, help="Exit 1 when the files differ from the models.")
def crds(out_dir: Path, docs_dir: Path, check: bool) -> None:
    """Generate CustomResourceDefinitions (and their reference doc) from the pydantic models."""
    from simtest_operator.api import crddocs, crdgen

    drift = [out_dir / name for name in crdgen.sync(out_dir, check=check)]
    reference = docs_dir / crddocs.DOC_FILE
    text = crddocs.render()
    if not reference.exists() or reference.read_text(encoding="utf-8") != text:
        drift.append(reference)
        if not check:
            docs_dir.mkdir(parents=True, exist_ok=True)
            reference.write_text(text, encoding="utf-8")
    if check and drift:
        for path in drift:
            click.echo(f"drift: {path} differs from the models; run `simtest crds`")
        raise SystemExit(1)
    verb = "checked" if check else "wrote"
    click.echo(f"{verb} {len(crdgen.CRD_FILES)} CRDs in {out_dir} and {reference}")
