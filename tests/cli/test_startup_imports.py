"""What ``simtest`` imports before it does anything: start-up cost is paid only for what runs.

Covers: ``simtest --help`` in a fresh interpreter lists every command and imports no command
module and none of the heavy packages; the lazy listing is exactly click's eager one and every
summary kept in ``cli/main.py`` is its command's own first help paragraph; importing a command's
module loads none of the other commands' dependencies (SUMO, the Kubernetes client, PostgreSQL,
S3, numpy, omega-prime and its data-frame stack, matplotlib). Timings are not asserted here:
``bench/startup.py`` measures them.
"""

from __future__ import annotations

import json
import subprocess
import sys

import click
import pytest
from click.testing import CliRunner

from simtest_operator.cli import main

HEAVY = frozenset(
    {
        *("libsumo", "traci", "sumolib", "pyproj", "numpy", "lxml", "mcap"),
        *("kopf", "kubernetes", "psycopg", "boto3", "botocore", "pydantic", "jinja2", "yaml"),
        *("omega_prime", "betterosi", "pyarrow", "polars", "pandas", "matplotlib", "rich"),
    }
)
"""Packages ``simtest --help`` has no use for."""

SUMO = frozenset({"libsumo", "traci", "sumolib", "pyproj"})
KUBERNETES = frozenset({"kopf", "kubernetes"})
NOBODYS = frozenset(
    {"omega_prime", "betterosi", "pyarrow", "polars", "pandas", "matplotlib", "boto3", "botocore"}
)
"""Needed by no command at import: reading recordings, plots, S3 (the runner pod's upload)."""

OTHERS = {
    "compare": SUMO | KUBERNETES | {"numpy", "psycopg"},
    "crds": SUMO | KUBERNETES | {"numpy", "psycopg"},
    "dev-cluster": SUMO | {"kopf", "numpy", "psycopg"},
    "evaluate": SUMO | KUBERNETES | {"numpy", "psycopg"},
    "evidence": SUMO | KUBERNETES | {"numpy", "psycopg"},
    "operator": SUMO | {"numpy", "psycopg"},
    "package": SUMO | KUBERNETES | {"numpy", "psycopg"},
    "render": SUMO | KUBERNETES | {"numpy"},
    "report": SUMO | KUBERNETES | {"numpy"},
    "run": SUMO | KUBERNETES | {"numpy"},
    "scenario": KUBERNETES | {"psycopg", "pydantic", "jinja2", "rich"},
    "search": SUMO | KUBERNETES | {"numpy", "psycopg"},
    "submit": SUMO | {"kopf", "numpy"},
    "ui": SUMO | KUBERNETES | {"numpy", "psycopg"},
}
"""Command -> other commands' dependencies its module must not import."""


def loaded_by(body: str) -> tuple[str, set[str]]:
    """stdout of ``body`` run in a fresh interpreter, and the modules it left loaded."""
    code = (
        f"import json, sys\ntry:\n    {body}\nfinally:\n    print(json.dumps(sorted(sys.modules)))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False
    )
    assert done.returncode == 0, done.stderr
    output, _, modules = done.stdout.rstrip("\n").rpartition("\n")
    return output, set(json.loads(modules))


def test_help_imports_no_command_and_nothing_heavy() -> None:
    output, modules = loaded_by(
        "from simtest_operator.cli.main import main\n"
        "    sys.argv = ['simtest', '--help']\n"
        "    try:\n        main()\n    except SystemExit:\n        pass"
    )
    for name in main.COMMANDS:
        assert f"\n  {name} " in output
    assert {m.split(".")[0] for m in modules} & HEAVY == set()
    commands = {m for m in modules if m.startswith("simtest_operator.cli.")}
    assert commands == {"simtest_operator.cli.main"}


def test_lazy_listing_equals_clicks_eager_one() -> None:
    eager = click.Group(
        "simtest",
        commands={name: main.load(name) for name in main.COMMANDS},
        help=main.cli.help,
        params=main.cli.params,
        context_settings=main.cli.context_settings,
    )
    lazy = CliRunner().invoke(main.cli, ["--help"], prog_name="simtest")
    assert lazy.exit_code == 0
    assert lazy.output == CliRunner().invoke(eager, ["--help"], prog_name="simtest").output


@pytest.mark.parametrize("name", sorted(main.COMMANDS))
def test_summary_is_the_commands_own_help(name: str) -> None:
    help_text = main.load(name).help or ""
    first = " ".join(help_text.split("\n\n")[0].split())
    assert main.COMMANDS[name].summary == first, (
        f"the help of `simtest {name}` changed: copy its first paragraph into "
        f"COMMANDS[{name!r}].summary in src/simtest_operator/cli/main.py"
    )


@pytest.mark.parametrize("name", sorted(main.COMMANDS))
def test_a_command_loads_no_other_commands_dependencies(name: str) -> None:
    module = main.COMMANDS[name].target.partition(":")[0]
    _, modules = loaded_by(f"import {module}")
    assert {m.split(".")[0] for m in modules} & (OTHERS[name] | NOBODYS) == set()


def test_every_command_has_its_list() -> None:
    assert set(OTHERS) == set(main.COMMANDS)
