"""``simtest dev-cluster``: build, start, inspect and stop the local control plane.

Wiring only: options in, one ``DevCluster`` call, formatted output. Defaults come from
``Settings`` (``SIMTEST_CACHE_DIR``): binaries in ``<cache>/toolchain``, clusters in
``<cache>/devcluster/<name>``.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

import click

from simtest_operator import devcluster
from simtest_operator.errors import SimtestError
from simtest_operator.settings import Settings


def _cluster(name: str, root: Path | None, settings: Settings) -> devcluster.DevCluster:
    cache = settings.cache
    return devcluster.DevCluster(
        root or cache.root / "devcluster" / name, devcluster.Toolchain(root=cache.toolchain)
    )


@contextlib.contextmanager
def _reported() -> Iterator[None]:
    """Show a project error as a one-paragraph message and exit 1, not as a traceback."""
    try:
        yield
    except SimtestError as exc:
        raise click.ClickException(str(exc)) from exc


_name = click.option(
    "--name",
    default="default",
    show_default=True,
    help="Cluster name (its folder under <cache>/devcluster/).",
)
_root = click.option(
    "--root",
    type=click.Path(path_type=Path),
    default=None,
    help="Cluster folder (overrides --name).",
)


@click.group("dev-cluster")
def dev_cluster() -> None:
    """A real Kubernetes control plane, fake (kwok) nodes and a real node, as local processes."""


@dev_cluster.command()
@click.argument("components", nargs=-1)
def build(components: tuple[str, ...]) -> None:
    """Build (or verify the cache of) etcd, kubernetes, kwok, helm and helmfile."""
    settings = Settings.from_env()
    log = settings.cache.toolchain / "build.log"
    with _reported():
        script = devcluster.find_build_script(Path.cwd())
        click.echo(f"building with {script} (log: {log}) ...")
        tc = devcluster.build_toolchain(
            script, cache_root=settings.cache.root, log_file=log, components=components
        )
    click.echo(f"binaries in {tc.bin_dir}")


@dev_cluster.command()
@_name
@_root
@click.option("--nodes", default=3, show_default=True, help="Number of fake nodes.")
@click.option(
    "--slots", default=3, show_default=True, help="simtest.dev/simulator capacity of each node."
)
@click.option("--gpus", default=1, show_default=True, help="nvidia.com/gpu capacity of each node.")
@click.option(
    "--crds",
    "crds_dir",
    type=click.Path(path_type=Path),
    default=Path("crds"),
    show_default=True,
    help="Folder of CRD YAML files to install (skipped if absent).",
)
@click.option("--port", type=int, default=None, help="apiserver port (default: a free one).")
@click.option(
    "--real-nodes",
    type=click.IntRange(0, 1),
    default=0,
    show_default=True,
    help="Nodes with a real kubelet, containerd and runc (needs root; at most one per machine).",
)
@click.option(
    "--kueue",
    "with_kueue",
    is_flag=True,
    help="Also start Kueue (built by `dev-cluster build`) so campaigns with "
    "spec.execution.queueName are admitted by its ClusterQueues (docs/kueue.md).",
)
def up(
    name: str,
    root: Path | None,
    nodes: int,
    slots: int,
    gpus: int,
    crds_dir: Path,
    port: int | None,
    real_nodes: int,
    with_kueue: bool,
) -> None:
    """Start the cluster (or report the running one) and wait until it is usable."""
    settings = Settings.from_env()
    cluster = _cluster(name, root, settings)
    with _reported():
        real_node = None
        if real_nodes:
            real_node = devcluster.real_node_setup(
                settings.cache.root,
                helm=cluster.toolchain.binary("helm"),
                chart=devcluster.find_chart(Path.cwd()),
                slots=slots,
            )
        info = cluster.up(
            nodes=nodes,
            shape=devcluster.NodeShape(simulator_slots=slots, gpus=gpus),
            crds_dir=crds_dir,
            apiserver_port=port,
            real_node=real_node,
            with_kueue=with_kueue,
        )
    took = f" in {info.startup_seconds:.1f}s" if info.startup_seconds is not None else ""
    click.echo(f"dev cluster up{took}: {info.server}")
    click.echo(f"  nodes: {', '.join(info.nodes) or '(none)'} ({slots} simulator slots each)")
    if info.real_nodes:
        click.echo(
            f"  real nodes: {', '.join(info.real_nodes)} (kubelet + containerd, {slots} simulator"
            " slots from the device plugin)"
        )
    click.echo(f"  CRDs:  {', '.join(info.crds) or '(none found in ' + str(crds_dir) + ')'}")
    if with_kueue:
        click.echo("  kueue: running (webhooks not registered; see docs/kueue.md)")
    click.echo(f"  logs:  {info.logs_dir}")
    click.echo(f"  export KUBECONFIG={info.kubeconfig}")


@dev_cluster.command()
@_name
@_root
def down(name: str, root: Path | None) -> None:
    """Stop the processes `up` started (logs and PKI stay)."""
    with _reported():
        stopped = _cluster(name, root, Settings.from_env()).down()
    click.echo(f"stopped: {', '.join(stopped)}" if stopped else "nothing was running")


@dev_cluster.command()
@_name
@_root
def status(name: str, root: Path | None) -> None:
    """Show each component's pid and whether the apiserver is ready; exit 1 unless running."""
    with _reported():
        st = _cluster(name, root, Settings.from_env()).status()
    if not st.started:
        click.echo(f"not started ({st.root})")
        raise SystemExit(1)
    click.echo(f"server: {st.server} ({'ready' if st.apiserver_ready else 'NOT ready'})")
    for c in st.components:
        click.echo(f"  {c.name:<24} pid {c.pid:<8} {'running' if c.alive else 'DEAD'}  {c.log}")
    if not st.running:
        raise SystemExit(1)


@dev_cluster.command("kubeconfig")
@_name
@_root
@click.option("--path", "path_only", is_flag=True, help="Print the file's path, not its content.")
def kubeconfig_cmd(name: str, root: Path | None, path_only: bool) -> None:
    """Print the admin kubeconfig, or with --path where it is.

    Use it as `export KUBECONFIG=$(simtest dev-cluster kubeconfig --path)`.
    """
    with _reported():
        info = _cluster(name, root, Settings.from_env()).info()
    click.echo(str(info.kubeconfig) if path_only else info.kubeconfig.read_text(), nl=path_only)
