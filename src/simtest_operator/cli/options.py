"""Click options that more than one command takes, defined once so name, type and help agree.

A decorator here is one option (or :func:`stack`, a fixed group) exactly as every command that
takes it declares it; an option only one command has stays in that command's module. Kept free of
heavy imports: every command module imports it.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import click

F = TypeVar("F", bound=Callable[..., object])


def stack(*decorators: Callable[[F], F]) -> Callable[[F], F]:
    """One decorator for ``decorators`` written in this order above a command (first on top)."""

    def apply(function: F) -> F:
        for decorator in reversed(decorators):
            function = decorator(function)
        return function

    return apply


kubeconfig = click.option(
    "--kubeconfig",
    type=click.Path(exists=True, dir_okay=False, path_type=Path),
    help="Kubeconfig to use; default: in-cluster service account, else $KUBECONFIG.",
)
"""The cluster to talk to (``simtest operator``, ``simtest submit``)."""
