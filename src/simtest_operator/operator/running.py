"""Running the operator: configure kopf, register the handlers, hand kopf our memo.

``simtest operator`` reads the configuration once and calls :func:`run` (through the package's
public entry); ``kopf run -m simtest_operator.operator.handlers`` works too (configuration then
comes from ``SIMTEST_OPERATOR_*`` variables and the credentials from ``$KUBECONFIG`` or the
in-cluster service account).
"""

from __future__ import annotations

import dataclasses
import importlib
import logging
import threading
from collections.abc import Sequence
from pathlib import Path

import kopf

from simtest_operator.operator.client import load_credentials
from simtest_operator.settings import OperatorSettings


def run(
    config: OperatorSettings,
    *,
    namespaces: Sequence[str] = (),
    kubeconfig: Path | None = None,
    verbose: bool = False,
    stop_flag: threading.Event | None = None,
    ready_flag: threading.Event | None = None,
) -> None:
    """Run until stopped (SIGINT/SIGTERM or ``stop_flag``); watches ``namespaces`` or, when
    empty, the whole cluster."""
    importlib.import_module("simtest_operator.operator.handlers")  # registers the handlers
    kopf.configure(verbose=verbose, log_format=kopf.LogFormat.PLAIN)
    logging.getLogger("aiohttp.access").setLevel(logging.WARNING)
    if not verbose:
        # kopf reports every handler call per object ("Handler ... succeeded"): five lines per
        # scenario at scale; our own loggers say what matters.
        logging.getLogger("kopf.objects").setLevel(logging.WARNING)
    if config.leadership.enabled and not config.leadership.lease_namespace and namespaces:
        leadership = dataclasses.replace(config.leadership, lease_namespace=namespaces[0])
        config = dataclasses.replace(config, leadership=leadership)
    memo = kopf.Memo(
        config=config,
        credentials=load_credentials(kubeconfig),
    )
    kopf.run(
        clusterwide=not namespaces,
        namespaces=list(namespaces),
        memo=memo,
        standalone=True,
        stop_flag=stop_flag,
        ready_flag=ready_flag,
    )
