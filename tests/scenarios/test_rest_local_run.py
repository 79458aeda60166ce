"""``simtest run`` over a REST scenario database (the CLI with the fake engine, a real server).

Covers: a campaign with a ``rest`` source (token from ``SIMTEST_SECRET_<NAME>_<KEY>``, inline and
URL items) resolves, pins inline items as ``rest+URL#id`` and runs each with its verdict; a
``--frozen`` rerun asks the database again and runs the same bytes; a database that changed an
item since is an Error of that scenario (never Invalid), and a missing token is exit 2 with the
variable to set.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator.cli.main import cli
from tests.runner.support import fake_xosc
from tests.scenarios.support import Routes

pytestmark = pytest.mark.timeout(120)

TOKEN_VARIABLE = "SIMTEST_SECRET_SCENARIO_DB_TOKEN"


def manifest(tmp_path: Path, url: str) -> Path:
    path = tmp_path / "campaign.yaml"
    path.write_text(
        f"""apiVersion: simtest.dev/v1alpha1
kind: TestCampaign
metadata:
  name: rest-demo
spec:
  scenarios:
    sources:
      - rest:
          url: "{url}"
          secretRef: {{name: scenario-db, key: token}}
  execution:
    retries: 0
"""
    )
    return path


def serve(routes: Routes, base: str, inline: dict[str, str]) -> None:
    """The database: items inline plus one by URL; answers only with the right token."""
    routes.get["/files/by-url.xosc"] = (200, fake_xosc("pass").encode(), {})
    items = [{"id": name, "content": fake_xosc(b)} for name, b in inline.items()]
    items.append({"id": "by-url", "url": f"{base}/files/by-url.xosc"})
    routes.get["/api/v1/scenarios?suite=smoke"] = (200, json.dumps({"items": items}).encode(), {})


def invoke(tmp_path: Path, *args: str, token: str | None = "t0k3n") -> tuple[int, str]:
    env = {"SIMTEST_CACHE_DIR": str(tmp_path / "cache")}
    if token is not None:
        env[TOKEN_VARIABLE] = token
    result = CliRunner().invoke(cli, ["run", *args, "--engine", "fake", "--plain"], env=env)
    return result.exit_code, result.output


def verdicts(out: Path) -> dict[str, str]:
    found = {}
    for result in out.glob("scenarios/*/result.json"):
        data = json.loads(result.read_text())
        found[data["scenarioId"]] = data["verdict"]
    return found


def test_simtest_run_over_a_rest_database(tmp_path: Path, server: tuple[str, Routes]) -> None:
    base, routes = server
    serve(routes, base, {"cut-in/a": "pass", "b": "fail"})
    url = f"{base}/api/v1/scenarios?suite=smoke"
    path = manifest(tmp_path, url)
    code, output = invoke(tmp_path, str(path), "-o", str(tmp_path / "out"))
    assert code == 1, output
    assert verdicts(tmp_path / "out") == {
        "cut-in/a.xosc": "Passed",
        "b.xosc": "Failed",
        "by-url.xosc": "Passed",
    }
    frozen = json.loads((tmp_path / "out" / "frozen.json").read_text())
    sources = {s["id"]: s["source"] for s in frozen["scenarios"]}
    assert sources["cut-in/a.xosc"] == f"rest+{url}#cut-in/a"
    assert sources["by-url.xosc"] == f"{base}/files/by-url.xosc"
    assert frozen["sources"][0]["kind"] == "rest"
    assert all(
        r[2].get("Authorization") == "Bearer t0k3n" for r in routes.requests if "api" in r[1]
    )

    frozen_file = tmp_path / "out" / "frozen.json"
    code, output = invoke(
        tmp_path, str(path), "--frozen", str(frozen_file), "-o", str(tmp_path / "again")
    )
    assert code == 1, output
    assert verdicts(tmp_path / "again") == verdicts(tmp_path / "out")

    serve(routes, base, {"cut-in/a": "fail", "b": "fail"})  # the database changed an item
    code, output = invoke(
        tmp_path, str(path), "--frozen", str(frozen_file), "-o", str(tmp_path / "changed")
    )
    changed = json.loads(
        next((tmp_path / "changed").glob("scenarios/cut-in__a*/result.json")).read_text()
    )
    assert (changed["verdict"], code) == ("Error", 2), output
    assert "changed since the list was frozen" in changed["reason"]


def test_a_missing_token_names_the_variable(tmp_path: Path, server: tuple[str, Routes]) -> None:
    base, routes = server
    serve(routes, base, {"a": "pass"})
    path = manifest(tmp_path, f"{base}/api/v1/scenarios?suite=smoke")
    code, output = invoke(tmp_path, str(path), "-o", str(tmp_path / "out"), token=None)
    assert code == 2, output
    assert f"Secret scenario-db/token is not available locally; set {TOKEN_VARIABLE}" in output
