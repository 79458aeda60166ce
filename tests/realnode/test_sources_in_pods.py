"""Every scenario source kind of ``simtest run`` works for a campaign on the real node.

Covers, one campaign per kind, each submitted with ``simtest submit --wait`` and run in real
containers (namespace enforcing Pod Security ``restricted``): ``configMap`` (scenarios plus the
road network they name as sibling keys; the operator mounts the ConfigMap read-only into the pod),
``git`` over the dumb HTTP protocol (a bare repository after ``git update-server-info`` served by
a Python HTTP server; the pod fetches the pinned commit itself), ``http`` (a .tar.gz archive),
``graphql`` (items delivered inline by the query, behind a bearer token from a Secret that
reaches the pod through ``secretKeyRef``) and ``rest`` (inline items of a GET of JSON). Each
campaign ends with exactly the verdicts ``simtest run`` gives on this machine for the same
scenarios, and no scenario ends ``Error`` or ``Invalid`` because the pod could not read what the
operator resolved.

The servers listen on loopback; ``expose`` forwards them to the node's bridge gateway address,
which the pods (and the operator, on this host) reach, as they would a service of the node
network on a real cluster.
"""

from __future__ import annotations

import http.server
import io
import json
import os
import shutil
import subprocess
import sys
import tarfile
import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
from kubernetes import client

from simtest_operator.devcluster.state import ClusterInfo
from tests.e2e import support
from tests.realnode.conftest import SCENARIOS, SMOKE
from tests.realnode.test_real_node import PodWatch

pytestmark = pytest.mark.timeout(600)  # operator start, a real campaign, then `simtest run`

PAIR = ("cut-in_highway_v25_gap30_dv5.xosc", "cut-in_highway_v30_gap8_dv12.xosc")
"""Two smoke scenarios on ``highway_straight``: one the driver model passes, one it fails."""
ROAD = "highway_straight.xodr"
CARLA = support.REPO / "tests" / "openscenario" / "carla" / "town01_carla_frame.xosc"
"""A scenario that names its road network by town (shipped with the runner), so a database can
deliver it inline without any other file."""
TOKEN = "e2e-scenario-db-token"
SECRET = {"name": "scenario-db", "key": "token"}
KINDS = ("configMap", "git", "http", "graphql", "rest")


class Served:
    """A loopback HTTP server: static files below ``root`` (the git repository, the archive),
    ``POST /graphql`` (bearer token required) and ``GET /api/scenarios`` answering with
    ``items``; every request is logged as (method, path, authorised)."""

    def __init__(self, root: Path, items: list[dict[str, str]]) -> None:
        self.items = items
        self.requests: list[tuple[str, str, bool]] = []
        served = self

        class Handler(http.server.SimpleHTTPRequestHandler):
            def __init__(self, *args: Any, **kwargs: Any) -> None:
                super().__init__(*args, directory=str(root), **kwargs)

            def log_message(self, format: str, *args: object) -> None:
                del format, args

            def _authorised(self) -> bool:
                return self.headers.get("Authorization") == f"Bearer {TOKEN}"

            def _json(self, status: int, document: Any) -> None:
                body = json.dumps(document).encode()
                self.send_response(status)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)

            def do_GET(self) -> None:
                served.requests.append(("GET", self.path, self._authorised()))
                if self.path.startswith("/api/scenarios"):
                    self._json(200, {"items": served.items})
                else:
                    super().do_GET()

            def do_POST(self) -> None:
                length = int(self.headers.get("Content-Length", "0"))
                self.rfile.read(length)
                served.requests.append(("POST", self.path, self._authorised()))
                if not self._authorised():
                    self._json(401, {"errors": [{"message": "unauthorised"}]})
                else:
                    self._json(200, {"data": {"scenarios": served.items}})

        self.httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.port = self.httpd.server_address[1]
        self._thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)
        self._thread.start()

    def close(self) -> None:
        self.httpd.shutdown()
        self.httpd.server_close()
        self._thread.join(timeout=5)


def smoke_tree(folder: Path) -> Path:
    """``smoke/<the pair>`` and ``roads/<ROAD>``: the layout the scenarios' ``../roads`` needs."""
    (folder / "smoke").mkdir(parents=True)
    (folder / "roads").mkdir()
    for name in PAIR:
        shutil.copy(SCENARIOS / "smoke" / name, folder / "smoke" / name)
    shutil.copy(SCENARIOS / "roads" / ROAD, folder / "roads" / ROAD)
    return folder


def flat_files() -> dict[str, str]:
    """The pair naming the road as a sibling file (ConfigMap keys cannot hold folders)."""
    files = {
        name: (SCENARIOS / "smoke" / name)
        .read_text(encoding="utf-8")
        .replace(f"../roads/{ROAD}", ROAD)
        for name in PAIR
    }
    files[ROAD] = (SCENARIOS / "roads" / ROAD).read_text(encoding="utf-8")
    return files


def git(cwd: Path, *args: str) -> str:
    env = {**os.environ, "GIT_CONFIG_GLOBAL": "/dev/null", "GIT_CONFIG_NOSYSTEM": "1"}
    done = subprocess.run(
        ["git", "-c", "user.name=e2e", "-c", "user.email=e2e@example.org", *args],
        cwd=cwd, env=env, capture_output=True, text=True, check=True,
    )  # fmt: skip
    return done.stdout.strip()


def dumb_repository(root: Path, work: Path) -> str:
    """A bare repository of the smoke tree at ``root/suite.git`` for the dumb HTTP protocol;
    returns its commit."""
    smoke_tree(work)
    git(work, "init", "--quiet", "--initial-branch=main")
    git(work, "add", ".")
    git(work, "commit", "--quiet", "-m", "scenarios")
    git(root, "clone", "--quiet", "--bare", str(work), "suite.git")
    git(root / "suite.git", "update-server-info")
    return git(work, "rev-parse", "HEAD")


def archive(root: Path, work: Path) -> None:
    """``root/suite.tar.gz``: the smoke tree."""
    smoke_tree(work)
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz") as tar:
        tar.add(work, arcname=".")
    (root / "suite.tar.gz").write_bytes(buffer.getvalue())


STORY = """
    <Story name="slow-down">
      <Act name="act">
        <ManeuverGroup name="ego" maximumExecutionCount="1">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="Ego"/></Actors>
          <Maneuver name="brake">
            <Event name="brake" priority="overwrite">
              <Action name="brake"><PrivateAction><LongitudinalAction><SpeedAction>
                <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
                <SpeedActionTarget><AbsoluteTargetSpeed value="5"/></SpeedActionTarget>
              </SpeedAction></LongitudinalAction></PrivateAction></Action>
              <StartTrigger><ConditionGroup><Condition name="t" delay="0" conditionEdge="none">
                <ByValueCondition><SimulationTimeCondition value="2" rule="greaterThan"/>
                </ByValueCondition></Condition></ConditionGroup></StartTrigger>
            </Event>
          </Maneuver>
        </ManeuverGroup>
        <StartTrigger><ConditionGroup><Condition name="go" delay="0" conditionEdge="none">
          <ByValueCondition><SimulationTimeCondition value="0" rule="greaterOrEqual"/>
          </ByValueCondition></Condition></ConditionGroup></StartTrigger>
      </Act>
    </Story>
"""


def inline_items() -> list[dict[str, str]]:
    """Two CARLA-authored scenarios (a town by name, CARLA's frame) that run for two seconds:
    a ScenarioRunner scenario ends with its stories, and a recording of one frame backs no
    verdict."""
    text = CARLA.read_text(encoding="utf-8").replace("</Init>", "</Init>" + STORY, 1)
    return [
        {"id": "carla/town01", "content": text},
        {"id": "carla/town01-again", "content": text + "<!-- a second item -->\n"},
    ]


def campaign(path: Path, name: str, sources: list[dict[str, Any]], include: list[str]) -> Path:
    """The smoke campaign renamed, over ``sources``, no retries (a fetch failure would show)."""
    manifest = yaml.safe_load(SMOKE.read_text(encoding="utf-8"))
    manifest["metadata"]["name"] = name
    manifest["spec"]["scenarios"]["sources"] = sources
    manifest["spec"]["scenarios"]["include"] = include
    manifest["spec"]["execution"]["retries"] = 0
    path.write_text(yaml.safe_dump(manifest), encoding="utf-8")
    return path


def local_verdicts(manifest: Path, out: Path) -> dict[str, str]:
    """``simtest run`` of ``manifest`` on this machine (the token as ``simtest run`` reads it)."""
    simtest = str(Path(sys.executable).parent / "simtest")
    done = subprocess.run(
        [simtest, "run", str(manifest), "-o", str(out), "--plain"],
        capture_output=True, text=True, check=False, timeout=600,
        # The cache below the test's folder: under /root (root's default) the loader would
        # refuse every fetched scenario as "in a system folder".
        env={
            **os.environ,
            "SIMTEST_SECRET_SCENARIO_DB_TOKEN": TOKEN,
            "SIMTEST_CACHE_DIR": str(out.parent / "local-cache"),
        },
    )  # fmt: skip
    verdicts = {}
    for result in out.glob("scenarios/*/result.json"):
        data = json.loads(result.read_text())
        verdicts[data["scenarioId"]] = data["verdict"]
    assert verdicts, done.stdout + done.stderr
    return verdicts


@pytest.fixture
def served(tmp_path: Path) -> Iterator[Served]:
    root = tmp_path / "www"
    root.mkdir()
    server = Served(root, inline_items())
    try:
        yield server
    finally:
        server.close()


@pytest.mark.parametrize("kind", KINDS)
def test_each_source_kind_runs_in_real_pods_with_the_local_verdicts(
    kind: str,
    real_cluster: ClusterInfo,
    real_api_client: client.ApiClient,
    real_namespace: str,
    real_operator: support.OperatorProcess,
    served: Served,
    expose: Callable[[int], str],
    tmp_path: Path,
) -> None:
    core = client.CoreV1Api(real_api_client)
    www = tmp_path / "www"  # what ``served`` serves
    base = f"http://{expose(served.port)}"
    name = f"src-{kind.lower()}"
    local_manifest: Path | None = None
    include = ["smoke/*.xosc"]
    if kind == "configMap":
        files = flat_files()
        core.create_namespaced_config_map(
            real_namespace, body={"metadata": {"name": "suite"}, "data": files}
        )
        sources: list[dict[str, Any]] = [{"configMap": {"name": "suite"}}]
        include = ["*.xosc"]
        flat = tmp_path / "flat"
        flat.mkdir()
        for key, text in files.items():
            (flat / key).write_text(text, encoding="utf-8")
        local_manifest = campaign(tmp_path / "local.yaml", name, [{"path": str(flat)}], include)
    elif kind == "git":
        commit = dumb_repository(www, tmp_path / "work")
        sources = [{"git": {"url": f"{base}/suite.git", "revision": commit}}]
    elif kind == "http":
        archive(www, tmp_path / "work")
        sources = [{"http": {"url": f"{base}/suite.tar.gz"}}]
    elif kind == "graphql":
        core.create_namespaced_secret(
            real_namespace,
            body={"metadata": {"name": SECRET["name"]}, "stringData": {SECRET["key"]: TOKEN}},
        )
        query = "query($suite: String) { scenarios(suite: $suite) { id content } }"
        sources = [
            {
                "graphql": {
                    "endpoint": f"{base}/graphql",
                    "query": query,
                    "variables": {"suite": "carla"},
                    "secretRef": SECRET,
                }
            }
        ]
        include = ["carla/*.xosc"]
    else:
        sources = [{"rest": {"url": f"{base}/api/scenarios?suite=carla"}}]
        include = ["carla/*.xosc"]
    manifest = campaign(tmp_path / f"{name}.yaml", name, sources, include)

    with PodWatch(real_api_client, real_namespace) as seen:
        submitted = support.submit(
            manifest, namespace=real_namespace, kubeconfig=real_cluster.kubeconfig, timeout=300
        )
    cluster = support.Cluster(real_api_client, real_namespace)
    results = cluster.results(name)
    verdicts = {scenario: r["verdict"] for scenario, r in results.items()}
    reasons = {scenario: r.get("reason", "") for scenario, r in results.items()}
    assert len(verdicts) == 2, (
        submitted.stdout,
        submitted.stderr,
        real_operator.log_text()[-3000:],
    )
    assert not {"Error", "Invalid"} & set(verdicts.values()), reasons
    assert verdicts == local_verdicts(local_manifest or manifest, tmp_path / "local")
    assert submitted.returncode == (1 if "Failed" in verdicts.values() else 0), submitted.stdout

    pods = list(seen.pods.values())
    assert pods, "the campaign ran no pod"
    for pod in pods:
        spec = pod.spec
        mounts = {m.mount_path for m in spec.containers[0].volume_mounts or []}
        volumes = [v for v in spec.volumes or [] if v.config_map is not None]
        env = {e.name: e for e in spec.containers[0].env or []}
        if kind == "configMap":
            assert "/var/run/simtest/configmaps/suite" in mounts
            assert [v.config_map.name for v in volumes] == ["suite"]
        else:
            assert volumes == []
        if kind == "graphql":
            token = env["SIMTEST_SOURCE_TOKEN_0"].value_from.secret_key_ref
            assert (token.name, token.key) == (SECRET["name"], SECRET["key"])
            assert TOKEN not in json.dumps([e.to_dict() for e in env.values()])
    if kind in ("graphql", "rest"):
        # Resolution by the operator, one query per pod, and the local run (resolve + none):
        # the pods asked the database themselves for the inline items.
        asked = [r for r in served.requests if r[1].startswith(("/graphql", "/api/"))]
        assert len(asked) >= 1 + len(pods), served.requests
        if kind == "graphql":
            assert all(authorised for _, _, authorised in asked)
