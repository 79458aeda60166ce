"""The ``simtest`` command: wiring only.

Each sub-command lives in its own module of this package, parses its options, calls one function
of a lower layer and formats what it returns (helm's ``pkg/cmd`` -> ``pkg/action`` split).
"""

from __future__ import annotations

import click

from simtest_operator import __version__
from simtest_operator.cli import crds, devcluster, scenario
from simtest_operator.cli import operator as operator_command
from simtest_operator.cli import package as package_command
from simtest_operator.cli import report as report_command
from simtest_operator.cli import run as run_command
from simtest_operator.cli import submit as submit_command


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="simtest")
def cli() -> None:
    """Scenario-based simulation testing for automated driving, on Kubernetes or locally."""


cli.add_command(crds.crds)
cli.add_command(scenario.scenario)
cli.add_command(devcluster.dev_cluster)
cli.add_command(report_command.report)
cli.add_command(package_command.package)
cli.add_command(run_command.run)
cli.add_command(operator_command.operator)
cli.add_command(submit_command.submit)


def main() -> None:
    """Console-script entry point."""
    cli(prog_name="simtest")
