"""The Kubernetes operator: TestCampaigns in, simulator pods and verdicts out.

This module is the package's public entry, and the only part of it the CLI may import
(import-linter enforces that): run the operator (:func:`run`), preview the environment request
it would build for one scenario (:func:`environment_request`), and submit a campaign to a cluster
and follow it (:func:`connect`, :class:`CampaignClient`). Everything else in the package is
internal. kopf loads only when :func:`run` is called.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from pathlib import Path

from simtest_operator.operator.previewing import environment_request
from simtest_operator.operator.submitting import CampaignClient, connect
from simtest_operator.settings import OperatorSettings

__all__ = ["CampaignClient", "connect", "environment_request", "run"]


def run(
    config: OperatorSettings,
    *,
    namespaces: Sequence[str] = (),
    kubeconfig: Path | None = None,
    verbose: bool = False,
    stop_flag: threading.Event | None = None,
    ready_flag: threading.Event | None = None,
) -> None:
    """Run the operator with ``config`` until stopped (SIGINT/SIGTERM or ``stop_flag``); watches
    ``namespaces`` or, when empty, the whole cluster."""
    from simtest_operator.operator import running  # kopf loads only here

    running.run(
        config,
        namespaces=namespaces,
        kubeconfig=kubeconfig,
        verbose=verbose,
        stop_flag=stop_flag,
        ready_flag=ready_flag,
    )
