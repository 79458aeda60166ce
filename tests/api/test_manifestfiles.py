"""Reading hostile manifest files (issue 12, item 3): one line naming the problem, exit 2.

Covers: non-UTF-8 bytes (with the line); nesting past MAX_DEPTH and 100k deep; a file past
MAX_BYTES (a 3-million-entry include list) refused before parsing, quickly and in little memory;
an alias bomb; a YAML syntax error on one line with "expected ',' or ']'" intact; a valid
manifest at the limits still loads; the same through ``simtest run``, ``simtest render`` and
``simtest submit`` (which reads the file before it contacts a cluster).
"""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator.api import manifestfiles
from simtest_operator.cli.main import cli
from simtest_operator.errors import ScenarioError

BASE = "apiVersion: simtest.dev/v1alpha1\nkind: TestCampaign\nmetadata: {name: demo}\n"
SPEC = "spec:\n  scenarios:\n    sources: [{path: suite}]\n"


def _nested(depth: int) -> str:
    return BASE + SPEC + "  x: " + "[" * depth + "]" * depth + "\n"


def _bomb() -> str:
    lines = ["  a0: &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]"]
    for i in range(1, 9):
        lines.append(f"  a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]")
    return BASE + SPEC + "\n".join(lines) + "\n"


def _huge_include() -> bytes:
    entries = b"".join(b"      - s%d.xosc\n" % i for i in range(3_000_000))
    return (BASE + SPEC + "    include:\n").encode() + entries


CASES = {
    "latin-1": ((BASE + SPEC).encode().replace(b"demo", b"d\xe9mo"),
                "manifest is not UTF-8 text: byte 0xe9 at line 3"),
    "deeper-than-the-limit": (_nested(manifestfiles.MAX_DEPTH + 1).encode(),
                              f"manifest nests deeper than {manifestfiles.MAX_DEPTH} levels"),
    "100k-deep": (_nested(100_000).encode(), "manifest "),
    "huge-include-list": (_huge_include(), "manifest is larger than 1536 KiB"),
    "alias-bomb": (_bomb().encode(), "manifest has more than 1000000 values once its aliases"),
    "unclosed-flow": ((BASE + "spec: {scenarios: [a, b\n").encode(),
                      "manifest is not valid YAML: line 5, column 1: did not find expected ',' "
                      "or ']' (while parsing a flow sequence)"),
}  # fmt: skip


@pytest.mark.parametrize("case", CASES)
def test_hostile_files_are_one_line_errors(tmp_path: Path, case: str) -> None:
    content, message = CASES[case]
    path = tmp_path / "m.yaml"
    path.write_bytes(content)
    started = time.monotonic()
    with pytest.raises(ScenarioError) as raised:
        manifestfiles.read(path)
    assert time.monotonic() - started < 5
    assert str(raised.value).startswith(message), str(raised.value)
    assert str(raised.value).endswith(f"({path})") and "\n" not in str(raised.value)


def test_a_manifest_within_the_limits_loads(tmp_path: Path) -> None:
    path = tmp_path / "m.yaml"
    path.write_text(_nested(manifestfiles.MAX_DEPTH - 2) + "  y: &v [1, 2]\n  z: [*v, *v]\n")
    text, [document] = manifestfiles.read(path)
    assert text == path.read_text()
    assert document["metadata"] == {"name": "demo"} and document["spec"]["z"] == [[1, 2], [1, 2]]


@pytest.mark.parametrize(
    "command", [["run", "--engine", "fake"], ["render", "--scenario", "a.xosc"], ["submit"]]
)
@pytest.mark.parametrize("case", ["latin-1", "100k-deep", "unclosed-flow"])
def test_every_command_exits_2_with_one_line(tmp_path: Path, command: list[str], case: str) -> None:
    path = tmp_path / "m.yaml"
    path.write_bytes(CASES[case][0])
    result = CliRunner().invoke(cli, [command[0], str(path), *command[1:]],
                                env={"SIMTEST_CACHE_DIR": str(tmp_path / "cache")})  # fmt: skip
    assert result.exit_code == 2, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)
    assert CASES[case][1].split(":")[0] in result.output
    assert result.output.count("\n") == 1, result.output


def test_many_unknown_keys_are_named_briefly_and_counted(tmp_path: Path) -> None:
    # 150,000 unknown top-level keys once made one 3.49 MB error line (issue 29).
    keys = "".join(f"k{i:05x}: 1\n" for i in range(150_000))  # 1.3 MB
    path = tmp_path / "m.yaml"
    path.write_text(BASE + SPEC + keys + "? " + "a" * 5000 + "\n: 1\n")  # a 5,000-character key
    result = CliRunner().invoke(cli, ["run", str(path), "--engine", "fake"],
                                env={"SIMTEST_CACHE_DIR": str(tmp_path / "cache")})  # fmt: skip
    assert result.exit_code == 2, result.output
    assert result.output.count("\n") == 1 and len(result.output) < 1000, result.output[:2000]
    assert f"{'a' * 119}…: unknown field; k00000: unknown field; k00001: unknown field;" in (
        result.output
    )
    assert "and 149,996 more (150,001 in all)" in result.output
