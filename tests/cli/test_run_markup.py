"""``simtest run`` prints user text verbatim: rich markup in names is never interpreted.

Covers (issue 12, item 2): scenario ids with ``[/x]`` and ``[bold]`` in the per-scenario lines,
the live view (``TTY_COMPATIBLE=1``), the not-passed table and the last line, with the right exit
code (1, not a MarkupError's 1 with a traceback); a manifest path with ``[/x]`` in the one-line
error; a YAML error's "expected ',' or ']'" kept intact.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator.cli.main import cli
from tests.runner.support import write_campaign

pytestmark = pytest.mark.timeout(120)
IDS = ("[/x].xosc", "ok[bold].xosc")
ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]|\r")


def _run(tmp_path: Path, *args: str, live: bool = False) -> tuple[int, str]:
    env = {"SIMTEST_CACHE_DIR": str(tmp_path / "cache"), "TTY_COMPATIBLE": "1" if live else "0"}
    result = CliRunner().invoke(cli, ["run", *args, "--engine", "fake"], env=env)
    assert result.exception is None or isinstance(result.exception, SystemExit), result.output
    return result.exit_code, ANSI.sub("", result.output)


@pytest.mark.parametrize("live", [False, True])
def test_scenario_ids_with_markup_are_printed_verbatim(tmp_path: Path, live: bool) -> None:
    manifest = write_campaign(tmp_path, {"[/x]": "fail", "ok[bold]": "pass"}, retries=1)
    code, output = _run(tmp_path, str(manifest), "-o", str(tmp_path / "o[/x]"), live=live)
    assert code == 1, output
    assert "MarkupError" not in output and "Traceback" not in output
    for ident in IDS if not live else IDS[:1]:
        assert ident in output
    assert "[/x].xosc │ Failed" in output  # the not-passed table
    assert f"output  {tmp_path / 'o[/x]'}" in output
    assert output.rstrip().splitlines()[-1].startswith("1 of 2 scenarios failed (first: [/x].xosc")


def test_a_manifest_path_with_markup_is_named_verbatim(tmp_path: Path) -> None:
    missing = tmp_path / "b[" / "x].yaml"
    code, output = _run(tmp_path, str(missing))
    assert code == 2, output
    assert output == f"error: cannot read manifest: No such file or directory ({missing})\n"


def test_a_yaml_error_keeps_its_brackets(tmp_path: Path) -> None:
    (tmp_path / "flow[").mkdir()
    manifest = tmp_path / "flow[" / "x].yaml"
    manifest.write_text("apiVersion: simtest.dev/v1alpha1\nspec:\n  sources: [{path: suite}\n")
    code, output = _run(tmp_path, str(manifest))
    assert code == 2, output
    assert "expected ',' or ']'" in output and str(manifest) in output
    assert "MarkupError" not in output


CONTROL = "\x1b[2J\r\n\u202eevil\x07"
"""ESC (clear screen), CR, newline, a right-to-left override and BEL: in a file name (issue 29)."""


@pytest.mark.parametrize("live", [False, True])
def test_control_characters_in_names_are_escaped(tmp_path: Path, live: bool) -> None:
    manifest = write_campaign(tmp_path, {f"a{CONTROL}": "fail"}, retries=1)
    result = CliRunner().invoke(
        cli,
        ["run", str(manifest), "--engine", "fake", "--plain", "-o", str(tmp_path / "o\x1bx")],
        env={"SIMTEST_CACHE_DIR": str(tmp_path / "cache"), "TTY_COMPATIBLE": str(int(live))},
    )
    assert result.exit_code == 1, result.output
    escaped = "a\\x1b[2J\\x0d\\x0a\\u202eevil\\x07.xosc"
    assert escaped in result.output
    assert "\u202e" not in result.output and "\x07" not in result.output
    assert "\x1b[2J" not in result.output and "\r" not in result.output
    assert "o\\x1bx" in result.output
