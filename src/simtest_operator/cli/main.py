"""The ``simtest`` command: wiring only.

Each sub-command lives in its own module of this package, parses its options, calls one function
of a lower layer and formats what it returns (helm's ``pkg/cmd`` -> ``pkg/action`` split).
Sub-command modules are imported only when their command runs: ``simtest operator`` never pays
for SUMO, and ``simtest run`` never for the Kubernetes client.
"""

from __future__ import annotations

import importlib

import click

from simtest_operator import __version__

COMMANDS = {
    "crds": "simtest_operator.cli.crds:crds",
    "dev-cluster": "simtest_operator.cli.devcluster:dev_cluster",
    "operator": "simtest_operator.cli.operator:operator",
    "package": "simtest_operator.cli.package:package",
    "render": "simtest_operator.cli.render:render",
    "report": "simtest_operator.cli.report:report",
    "run": "simtest_operator.cli.run:run",
    "scenario": "simtest_operator.cli.scenario:scenario",
    "submit": "simtest_operator.cli.submit:submit",
}
"""Command name -> ``module:attribute`` of its click command."""


class LazyGroup(click.Group):
    """A click group that imports a sub-command's module on first use."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted({*COMMANDS, *super().list_commands(ctx)})

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        target = COMMANDS.get(cmd_name)
        if target is None:
            return super().get_command(ctx, cmd_name)
        module_name, _, attribute = target.partition(":")
        command = getattr(importlib.import_module(module_name), attribute)
        if not isinstance(command, click.Command):
            raise TypeError(f"{target} is not a click command")
        return command


@click.group(cls=LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="simtest")
def cli() -> None:
    """Scenario-based simulation testing for automated driving, on Kubernetes or locally."""


def main() -> None:
    """Console-script entry point."""
    cli(prog_name="simtest")
