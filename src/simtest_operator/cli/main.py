"""The ``simtest`` command: wiring only.

Each sub-command lives in its own module of this package, parses its options, calls one function
of a lower layer and formats what it returns (helm's ``pkg/cmd`` -> ``pkg/action`` split).
Sub-command modules are imported only when their command runs: ``simtest operator`` never pays
for SUMO, ``simtest run`` never for the Kubernetes client, and ``simtest --help`` for none of
them -- it lists each command with the summary kept here (tests/cli/test_startup_imports.py
checks that every summary matches its command's own help).
"""

from __future__ import annotations

import dataclasses
import importlib

import click

from simtest_operator import __version__


@dataclasses.dataclass(frozen=True, slots=True)
class Entry:
    """Where a sub-command lives and what ``simtest --help`` says about it."""

    target: str
    """``module:attribute`` of its click command."""
    summary: str
    """The first paragraph of its help (click shortens it to the terminal's width)."""


COMMANDS = {
    "crds": Entry(
        "simtest_operator.cli.crds:crds",
        "Generate CustomResourceDefinitions (and their reference doc) from the pydantic models.",
    ),
    "dev-cluster": Entry(
        "simtest_operator.cli.devcluster:dev_cluster",
        "A real Kubernetes control plane, fake (kwok) nodes and a real node, as local processes.",
    ),
    "evidence": Entry(
        "simtest_operator.cli.evidence:evidence",
        "Export a campaign run's evidence bundle (verdicts, metrics and content hashes of "
        "scenario, map, SUT, simulator and recording) and verify one offline.",
    ),
    "evaluate": Entry(
        "simtest_operator.cli.evaluate:evaluate",
        "Re-score recorded runs with another criteria set, from their recordings alone.",
    ),
    "compare": Entry(
        "simtest_operator.cli.compare:compare",
        "Compare two runs' KPIs per scenario and base scenario; gate CI with --fail-on RULES.",
    ),
    "operator": Entry(
        "simtest_operator.cli.operator:operator",
        "Run the simtest operator: TestCampaigns in, simulator pods and verdicts out.",
    ),
    "package": Entry(
        "simtest_operator.cli.package:package",
        "Package applications as Helm charts and keep the charts' generated files current.",
    ),
    "render": Entry(
        "simtest_operator.cli.render:render",
        "Render the environment of one scenario of a TestCampaign MANIFEST, as the operator would.",
    ),
    "report": Entry(
        "simtest_operator.cli.report:report",
        "Write a self-contained HTML report of the run in OUTDIR (overview, coverage, "
        "per-scenario detail with trajectories, and a comparison with another run).",
    ),
    "run": Entry(
        "simtest_operator.cli.run:run",
        "Run a TestCampaign MANIFEST on this machine, in parallel worker processes.",
    ),
    "scenario": Entry(
        "simtest_operator.cli.scenario:scenario",
        "Run OpenSCENARIO files on the SUMO-backed simulator stand-in.",
    ),
    "search": Entry(
        "simtest_operator.cli.search:search",
        "What a finished search found: export its critical concrete scenarios.",
    ),
    "submit": Entry(
        "simtest_operator.cli.submit:submit",
        "Create the TestCampaign in MANIFEST on the cluster (and wait for its verdict).",
    ),
    "ui": Entry(
        "simtest_operator.cli.ui:ui",
        "Serve the results UI from a results database (SQLite or PostgreSQL).",
    ),
}
"""Command name -> its entry."""


def load(name: str) -> click.Command:
    """Import the module of command ``name`` and return its click command."""
    module_name, _, attribute = COMMANDS[name].target.partition(":")
    command = getattr(importlib.import_module(module_name), attribute)
    if not isinstance(command, click.Command):
        raise TypeError(f"{COMMANDS[name].target} is not a click command")
    return command


class LazyGroup(click.Group):
    """A click group that imports a sub-command's module on first use, not to list it."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted({*COMMANDS, *super().list_commands(ctx)})

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        if cmd_name in COMMANDS:
            return load(cmd_name)
        return super().get_command(ctx, cmd_name)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """click's listing, with a stand-in that carries the summary for each lazy command."""
        listed = []
        for name in self.list_commands(ctx):
            if name in COMMANDS:
                listed.append((name, click.Command(name, help=COMMANDS[name].summary)))
                continue
            command = super().get_command(ctx, name)
            if command is not None and not command.hidden:
                listed.append((name, command))
        if not listed:
            return
        limit = formatter.width - 6 - max(len(name) for name, _ in listed)
        with formatter.section("Commands"):
            formatter.write_dl([(name, c.get_short_help_str(limit)) for name, c in listed])


@click.group(cls=LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="simtest")
def cli() -> None:
    """Scenario-based simulation testing for automated driving, on Kubernetes or locally."""


def main() -> None:
    """Console-script entry point."""
    cli(prog_name="simtest")
