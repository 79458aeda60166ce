"""The simulator pod's runner fetching ConfigMap and database scenarios (``entrypoint.run_job``).

Covers: with the ConfigMaps mounted the way the kubelet mounts them and the run spec's databases
(a GraphQL one with inline content behind a bearer token from the pod's ``secretKeyRef``
variable, a REST one without a token), every scenario is fetched, verified and run; a ConfigMap
that is not mounted, a token variable that is unset and a database whose item changed each end
that scenario ``Error`` with the reason (retried by the operator), never ``Invalid``; the
secret provider only serves the keys the run spec lists.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import pytest

from simtest_operator.errors import SourceError
from simtest_operator.render import ScenarioRef, runspecs
from simtest_operator.runner import entrypoint
from simtest_operator.scenarios import GraphqlSource, RestSource, SecretRef, sha256_hex
from simtest_operator.settings import Settings
from simtest_operator.verdicts import Verdict
from tests.runner.podsupport import fake_run_one, job
from tests.runner.support import fake_xosc
from tests.scenarios.conftest import server  # noqa: F401  (the HTTP test server fixture)
from tests.scenarios.support import Routes

TOKEN = SecretRef(name="scenario-db", key="token")


def kubelet_volume(root: Path, name: str, data: dict[str, str]) -> None:
    """A configMap volume as the kubelet lays it out: keys link into ``..data``."""
    stamp = root / name / "..2026_11_24_10_00_00.1"
    stamp.mkdir(parents=True)
    for key, value in data.items():
        (stamp / key).write_text(value)
    (root / name / "..data").symlink_to(stamp.name)
    for key in data:
        (root / name / key).symlink_to(f"..data/{key}")


def ref(ident: str, source: str, content: str) -> ScenarioRef:
    return ScenarioRef(id=ident, source=source, sha256=sha256_hex(content.encode()))


def databases(routes: Routes, base: str, graphql_item: str, rest_item: str) -> None:
    def answer(path: str, headers: dict[str, str], payload: Any) -> tuple[int, bytes]:
        if headers.get("Authorization") != "Bearer pod-token":
            return 401, b"{}"
        rows = [{"id": "g1", "content": graphql_item}]
        return 200, json.dumps({"data": {"scenarios": rows}}).encode()

    routes.post = answer
    rows = json.dumps({"results": [{"id": "r1", "content": rest_item}]}).encode()
    routes.get["/api?suite=pods"] = (200, rows, {})


def pod_job(tmp_path: Path, base: str) -> entrypoint.Job:
    plain = job(tmp_path, {"unused": "pass"})
    spec = dataclasses.replace(
        plain.spec,
        isolation="PerScenario",
        scenarios=(
            ref("a.xosc", "configmap:suite/a.xosc", fake_xosc("pass")),
            ref("notes.txt", "configmap:suite/notes.txt", fake_xosc("fail")),
            ref("g1.xosc", f"graphql+{base}/graphql#g1", fake_xosc("pass")),
            ref("r1.xosc", f"rest+{base}/api?suite=pods#r1", fake_xosc("fail")),
            ref("gone.xosc", "configmap:gone/gone.xosc", fake_xosc("pass")),
        ),
        databases=(
            GraphqlSource(
                endpoint=f"{base}/graphql", query="{scenarios{id content}}", secret=TOKEN
            ),
            RestSource(url=f"{base}/api?suite=pods"),
        ),
    )
    return dataclasses.replace(plain, spec=spec)


def run(
    tmp_path: Path, the_job: entrypoint.Job, env: dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> dict[str, tuple[Verdict, str]]:
    root = tmp_path / "configmaps"
    if not root.exists():
        kubelet_volume(root, "suite", {"a.xosc": fake_xosc("pass"), "notes.txt": fake_xosc("fail")})
    monkeypatch.setattr(entrypoint, "CONFIG_MAP_ROOT", root)
    settings = Settings.from_env({**env, "SIMTEST_CACHE_DIR": str(the_job.settings.cache.root)})
    the_job = dataclasses.replace(the_job, settings=settings)
    attempts = entrypoint.run_job(the_job, run_one=fake_run_one, fork=False)
    return {a.outcome.scenario_id: (a.outcome.verdict, a.outcome.reason) for a in attempts}


def test_the_pod_fetches_config_map_and_database_scenarios(
    tmp_path: Path,
    server: tuple[str, Routes],  # noqa: F811
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    base, routes = server
    databases(routes, base, fake_xosc("pass"), fake_xosc("fail"))
    the_job = pod_job(tmp_path, base)
    variable = runspecs.secret_variables(the_job.spec.databases)[TOKEN]
    outcomes = run(tmp_path, the_job, {variable: "pod-token\n"}, monkeypatch)
    assert {k: v for k, (v, _) in outcomes.items()} == {
        "a.xosc": Verdict.PASSED,
        "notes.txt": Verdict.FAILED,
        "g1.xosc": Verdict.PASSED,
        "r1.xosc": Verdict.FAILED,
        "gone.xosc": Verdict.ERROR,
    }
    reason = outcomes["gone.xosc"][1]
    assert reason.startswith("the pod cannot fetch the pinned scenario: ConfigMap 'gone' is not")
    assert [r[1] for r in routes.requests] == ["/graphql", "/api?suite=pods"], "asked once each"


def test_unreachable_database_scenarios_are_errors_not_invalid(
    tmp_path: Path,
    server: tuple[str, Routes],  # noqa: F811
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    base, routes = server
    databases(routes, base, fake_xosc("pass"), fake_xosc("pass"))  # r1 changed since freezing
    outcomes = run(tmp_path, pod_job(tmp_path, base), {}, monkeypatch)  # no token variable
    assert outcomes["g1.xosc"][0] is Verdict.ERROR
    assert "Secret scenario-db/token is not available in the pod" in outcomes["g1.xosc"][1]
    assert "SIMTEST_SOURCE_TOKEN_0 is unset" in outcomes["g1.xosc"][1]
    assert outcomes["r1.xosc"][0] is Verdict.ERROR
    assert "changed since the list was frozen" in outcomes["r1.xosc"][1]
    assert Verdict.INVALID not in {v for v, _ in outcomes.values()}


def test_pod_secrets_serve_only_listed_keys(tmp_path: Path) -> None:
    spec = dataclasses.replace(
        job(tmp_path, {"a": "pass"}).spec,
        databases=(RestSource(url="https://db/api", secret=TOKEN),),
    )
    provide = entrypoint.pod_secrets(spec, {"SIMTEST_SOURCE_TOKEN_0": " t "})
    assert provide(TOKEN) == "t"
    with pytest.raises(SourceError, match="Secret other/k is not one the run spec lists"):
        provide(SecretRef(name="other", key="k"))
