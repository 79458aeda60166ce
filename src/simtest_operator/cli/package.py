"""``simtest package``: a ROS 2 application's chart from its spec; chart artefacts kept in sync."""

from __future__ import annotations

from pathlib import Path

import click

from simtest_operator.errors import RenderError


@click.group()
def package() -> None:
    """Package applications as Helm charts and keep the charts' generated files current."""


@package.command("ros")
@click.argument("spec", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option(
    "--out",
    "out_dir",
    type=click.Path(file_okay=False, path_type=Path),
    default=Path("dist/charts"),
    show_default=True,
    help="Folder the chart folder <name>/ is written to (replaced if present).",
)
@click.option(
    "--base-chart",
    type=click.Path(exists=True, file_okay=False, path_type=Path),
    default=Path("charts/k8s-ros"),
    show_default=True,
    help="The K8s-ROS base chart to depend on (and vendor).",
)
@click.option(
    "--vendor/--no-vendor",
    default=True,
    show_default=True,
    help="Copy the base chart into charts/ (offline, reproducible) or leave it to "
    "`helm dependency update` from the spec's base.repository.",
)
def ros(spec: Path, out_dir: Path, base_chart: Path, vendor: bool) -> None:
    """Generate the Helm chart of a ROS 2 application from its package SPEC (YAML)."""
    from simtest_operator.packaging import rospackaging

    try:
        inputs = rospackaging.load_inputs(spec, base_chart)
        files = rospackaging.chart_files(inputs, vendor=vendor)
    except RenderError as exc:
        raise click.ClickException(str(exc)) from exc
    target = rospackaging.write(files, out_dir, inputs.spec.name)
    click.echo(f"wrote {target} ({len(files)} files): {inputs.spec.name} {inputs.spec.version}")


@package.command("sync")
@click.option(
    "--root",
    type=click.Path(exists=True, file_okay=False, path_type=Path),
    default=Path(),
    show_default=True,
    help="Repository root.",
)
@click.option("--check", is_flag=True, help="Exit 1 when a generated file is out of date.")
def sync(root: Path, check: bool) -> None:
    """Copy crds/ into the operator chart and regenerate the values tables in docs/."""
    from simtest_operator.packaging import syncing

    try:
        drift = syncing.sync_all(root, check=check)
    except (OSError, RenderError) as exc:
        raise click.ClickException(str(exc)) from exc
    if check and drift:
        for path in drift:
            click.echo(f"drift: {path}; run `simtest package sync`")
        raise SystemExit(1)
    verb = "checked" if check else "synced"
    click.echo(f"{verb} chart artefacts under {root.resolve()} ({len(drift)} changed)")
