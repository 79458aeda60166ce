"""``simtest operator``: run the Kubernetes operator in the foreground.

The settings are read once here: flags override the ``SIMTEST_OPERATOR_*`` variables the chart
sets (``settings.OperatorSettings``). The operator package (and kopf with it) is imported only
when the command runs.
"""

from __future__ import annotations

from pathlib import Path

import click

from simtest_operator.cli import options
from simtest_operator.settings import Settings


@click.command("operator")
@click.option(
    "--namespace",
    "-n",
    "namespaces",
    multiple=True,
    help="Namespace to watch (repeatable); without it the whole cluster is watched.",
)
@options.kubeconfig
@click.option(
    "--templates",
    type=click.Path(exists=True, file_okay=False, path_type=Path),
    help="Environment templates root (default: ./helm-templates or $SIMTEST_OPERATOR_TEMPLATES).",
)
@click.option(
    "--sources",
    type=click.Path(exists=True, file_okay=False, path_type=Path),
    help="Folder that relative `path` scenario sources are resolved against.",
)
@click.option(
    "--cache",
    type=click.Path(file_okay=False, path_type=Path),
    help="Cache folder for resolved sources (downloads, git mirrors).",
)
@click.option(
    "--metrics-port",
    type=int,
    help="Port of /metrics, /healthz and /readyz (0 disables; default 8080).",
)
@click.option(
    "--keep-environments",
    is_flag=True,
    default=None,
    help="Keep finished SimEnvironments instead of deleting them once recorded.",
)
@click.option(
    "--leader-election",
    is_flag=True,
    default=None,
    help="Run campaign loops only while holding the Lease (for 2+ replicas).",
)
@click.option(
    "--identity",
    help="This replica's name in the Lease (default: the pod name, else host and pid).",
)
@click.option("--verbose", "-v", is_flag=True, help="Log every reconcile step.")
def operator(
    namespaces: tuple[str, ...],
    kubeconfig: Path | None,
    templates: Path | None,
    sources: Path | None,
    cache: Path | None,
    metrics_port: int | None,
    keep_environments: bool | None,
    leader_election: bool | None,
    identity: str | None,
    verbose: bool,
) -> None:
    """Run the simtest operator: TestCampaigns in, simulator pods and verdicts out."""
    from simtest_operator import operator as operating  # the operator's stack loads only here

    settings = Settings.from_env(
        operator_flags={
            "inputs.templates_dir": templates,
            "inputs.sources_dir": sources,
            "inputs.cache_dir": cache,
            "metrics_port": metrics_port,
            "keep_finished_environments": keep_environments,
            "leadership.enabled": leader_election,
            "leadership.identity": identity,
        }
    )
    operating.run(settings.operator, namespaces=namespaces, kubeconfig=kubeconfig, verbose=verbose)
