"""The CI pipeline examples in deploy/ci (GitHub Actions and GitLab CI).

Covers: both files parse; each runs `simtest submit <manifest> --wait --junit <file>` on the
manifest it prepared and keeps that JUnit file (artifact upload, GitLab junit report, also on
failure); cluster credentials come from a secret variable, never from the file; every option the
examples pass to `simtest submit` exists in the CLI.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path
from typing import Any

import click
import yaml

from simtest_operator.cli.main import cli

REPO = Path(__file__).resolve().parents[2]
CI = REPO / "deploy" / "ci"


def _commands(steps: list[str]) -> list[list[str]]:
    return [shlex.split(step) for step in steps if step.lstrip().startswith("simtest submit")]


def _github() -> tuple[dict[str, Any], list[list[str]]]:
    workflow = yaml.safe_load((CI / "github-actions.yml").read_text())
    steps = workflow["jobs"]["campaign"]["steps"]
    return workflow, _commands([step.get("run", "") for step in steps])


def _gitlab() -> tuple[dict[str, Any], list[list[str]]]:
    pipeline = yaml.safe_load((CI / "gitlab-ci.yml").read_text())
    return pipeline, _commands(pipeline["scenario-tests"]["script"])


def _junit(command: list[str]) -> str:
    assert command[:2] == ["simtest", "submit"]
    assert "--wait" in command and "--junit" in command
    return command[command.index("--junit") + 1]


def test_github_actions() -> None:
    workflow, commands = _github()
    assert len(commands) == 1
    report = _junit(commands[0])
    steps = workflow["jobs"]["campaign"]["steps"]
    upload = next(s for s in steps if s.get("uses", "").startswith("actions/upload-artifact"))
    assert upload["if"] == "always()" and upload["with"]["path"] == report
    text = (CI / "github-actions.yml").read_text()
    assert "secrets.KUBECONFIG_B64" in text
    assert workflow["permissions"] == {"contents": "read"}
    assert commands[0][2] == "campaign.yaml"
    assert "open('campaign.yaml', 'w')" in text  # the manifest it submits is the one it prepared


def test_gitlab_ci() -> None:
    pipeline, commands = _gitlab()
    assert len(commands) == 1
    report = _junit(commands[0])
    artifacts = pipeline["scenario-tests"]["artifacts"]
    assert artifacts["when"] == "always"
    assert artifacts["reports"]["junit"] == report and report in artifacts["paths"]
    assert "$KUBECONFIG_B64" in " ".join(pipeline["scenario-tests"]["before_script"])


def test_submit_options_exist_in_the_cli() -> None:
    submit = cli.get_command(click.Context(cli), "submit")
    assert submit is not None
    known = {
        opt for param in submit.params if isinstance(param, click.Option) for opt in param.opts
    }
    for command in _github()[1] + _gitlab()[1]:
        used = {word for word in command if re.match(r"^--?[a-z]", word)}
        assert used <= known, f"unknown options {sorted(used - known)}"
