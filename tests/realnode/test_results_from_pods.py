"""Results and artifacts flow from simulator pods in real containers on the real node.

Real SUMO smoke scenarios run in the runner image under the kubelet (which resolves the pod's
``secretKeyRef`` variables and mounts its volumes), a throw-away PostgreSQL server holds the
results database and moto's S3 server the artifacts bucket — both reached by the pods through the
node network, as on a cluster; the operator is the real ``simtest operator`` process.

Covers:

* a campaign with ``spec.results.databaseSecretRef`` and ``spec.artifacts.s3``: ScenarioBatch
  status and the database rows agree (one row per scenario attempt, under the run key
  ``recording_results.run_key`` gives), the operator marks the run finished with the campaign's
  final phase and counters, artifact URIs in status are ``s3://`` and name objects that exist
  (the recording is a readable MCAP, ``result.json`` carries the same URIs), and ``simtest
  report`` over that database names every scenario;
* ``spec.artifacts.pvc``: recordings, logs and result files land on the claim (a hostPath
  PersistentVolume on the node) below ``<subPath>/<campaign>/``, written by the pod's user;
* a database that is down (DSN at a closed port): the verdicts are unchanged, each result in
  ScenarioBatch status says ``resultsStored: false`` and the batch has a ``ResultsNotStored``
  Warning event;
* a DSN Secret that does not exist: the kubelet reports ``CreateContainerConfigError`` and the
  scenario ends as ``Error`` naming the Secret.
"""

from __future__ import annotations

import json
import subprocess
import sys
import urllib.parse
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import pytest
from kubernetes import client

from simtest_operator import recording, results
from simtest_operator.operator import observed, recording_results
from tests.e2e import support
from tests.realnode.conftest import (
    PREFIX,
    create_secret,
    host_path_claim,
    results_campaign,
    wait_for,
)
from tests.results.s3server import BUCKET, CREDENTIALS, S3Server, free_port, s3

__all__ = ["s3"]  # the fixture, used by name

FAILING = "cut-in_highway_v30_gap8_dv12.xosc"
"""The smoke suite's failure by design: the cut-in vehicle collides with the ego."""
PASSING = ("cut-in_highway_v25_gap30_dv5.xosc", "hard-braking_rural_v15_thw2_d4.xosc")


@pytest.fixture
def cluster(real_api_client: client.ApiClient, real_namespace: str) -> support.Cluster:
    return support.Cluster(real_api_client, real_namespace)


def _port(dsn: str) -> int:
    port = urllib.parse.urlsplit(dsn).port
    assert port is not None, dsn
    return port


def _run_key(cluster: support.Cluster, name: str) -> results.RunKey:
    return recording_results.run_key(observed.campaign_view(cluster.get("testcampaigns", name)))


def _check_verdicts(found: dict[str, dict[str, Any]], names: Sequence[str]) -> None:
    assert sorted(found) == sorted(names)
    assert found[FAILING]["verdict"] == "Failed"
    assert "collided" in found[FAILING]["reason"]
    assert all(found[n]["verdict"] == "Passed" for n in names if n != FAILING), found


@pytest.fixture
def artifacts_claim(
    real_api_client: client.ApiClient, real_namespace: str, tmp_path: Path
) -> Iterator[tuple[str, Path]]:
    """A ReadWriteMany claim on a hostPath PersistentVolume: a local-path style volume."""
    folder = tmp_path / "artifacts-volume"
    folder.mkdir()
    folder.chmod(0o1777)  # the pods run as 65532; hostPath volumes get no fsGroup ownership
    with host_path_claim(
        real_api_client, real_namespace, claim="artifacts", folder=folder, access="ReadWriteMany"
    ) as claim:
        yield claim, folder


def test_artifacts_land_on_a_persistent_volume_claim(
    real_operator: support.OperatorProcess,
    cluster: support.Cluster,
    artifacts_claim: tuple[str, Path],
    tmp_path: Path,
) -> None:
    claim, folder = artifacts_claim
    names = (FAILING, PASSING[0])
    cluster.create(
        results_campaign(
            tmp_path, "onpvc", names, database=None, pvc={"claimName": claim, "subPath": "runs"}
        )
    )
    cluster.wait_complete("onpvc", timeout=600, alive=real_operator.alive)
    found = cluster.results("onpvc")
    _check_verdicts(found, names)
    for scenario_id in names:
        (result_file,) = (folder / "runs" / "onpvc").glob(f"*/{scenario_id}/result.json")
        written = json.loads(result_file.read_text())
        assert written["verdict"] == found[scenario_id]["verdict"]
        mcap = result_file.parent / "recording.mcap"
        trajectories = recording.read_trajectories(mcap)
        assert len(trajectories) >= 2 and all(len(s) > 10 for s in trajectories.values())
        assert result_file.stat().st_uid == 65532  # written by the pod's user
        assert set(found[scenario_id]["artifacts"]) >= {"recording", "log", "result"}


@pytest.mark.postgres
@pytest.mark.slow
@pytest.mark.timeout(900)
def test_results_and_artifacts_flow_from_the_pods(
    real_operator: support.OperatorProcess,
    cluster: support.Cluster,
    postgres_dsn: str,
    s3: S3Server,
    expose: Callable[[int], str],
    tmp_path: Path,
) -> None:
    names = (FAILING, *PASSING)
    # Pods and the operator reach the database and the bucket through the node network.
    dsn = postgres_dsn.replace(f"127.0.0.1:{_port(postgres_dsn)}", expose(_port(postgres_dsn)))
    endpoint = f"http://{expose(s3.port)}"
    create_secret(cluster, "results-db", {"dsn": dsn})
    create_secret(
        cluster,
        "artifacts-s3",
        {
            "AWS_ACCESS_KEY_ID": CREDENTIALS["access_key_id"],
            "AWS_SECRET_ACCESS_KEY": CREDENTIALS["secret_access_key"],
        },
    )
    cluster.create(results_campaign(tmp_path, "results", names, database="results-db", s3=endpoint))
    status = cluster.wait_complete("results", timeout=600, alive=real_operator.alive)
    key = _run_key(cluster, "results")

    def finished() -> results.CampaignRecord | None:
        with results.open_store(postgres_dsn) as store:
            record = store.campaign(key)
        return record if record is not None and record.finished else None

    # The operator's recorder works in the background: wait for the run's end record.
    run = wait_for("the finished campaign record", finished, timeout=120)
    found = cluster.results("results")
    _check_verdicts(found, names)
    assert all("resultsStored" not in r for r in found.values())
    assert status["phase"] == "Failed" and status["total"] == 3

    # The database: one row per scenario attempt under the campaign's run key, same verdicts.
    with results.open_store(postgres_dsn) as store:
        rows = store.outcomes(key)
        listed = [s.scenario_id for s in store.scenarios(key)]
    assert sorted(r.scenario.scenario_id for r in rows) == sorted(names)
    for row in rows:
        result = found[row.scenario.scenario_id]
        assert row.outcome.verdict.value == result["verdict"]
        assert row.outcome.attempts == 1 == result["attempts"]
        assert row.outcome.artifacts == result["artifacts"]
        assert row.content_hashes["recording"]
    assert sorted(listed) == sorted(names)
    assert run.phase == status["phase"] == "Failed"
    assert run.info.namespace == cluster.namespace
    counts = {k: run.counts[k] for k in ("total", "passed", "failed", "errored")}
    assert counts == {"total": 3, "passed": 2, "failed": 1, "errored": 0}
    assert counts == {k: status[k] for k in counts}

    # The artifacts: s3:// URIs in status naming objects that exist in the bucket.
    keys = set(s3.keys())
    for scenario_id, result in found.items():
        artifacts = result["artifacts"]
        assert set(artifacts) >= {"recording", "log", "result"}, artifacts
        for uri in artifacts.values():
            assert uri.startswith(f"s3://{BUCKET}/{PREFIX}/results/"), uri
            assert uri.removeprefix(f"s3://{BUCKET}/") in keys, uri
        uploaded = json.loads(s3.read(artifacts["result"].removeprefix(f"s3://{BUCKET}/")))
        assert uploaded["artifacts"] == artifacts
        assert uploaded["verdict"] == result["verdict"]
        mcap = tmp_path / f"{scenario_id}.mcap"
        mcap.write_bytes(s3.read(artifacts["recording"].removeprefix(f"s3://{BUCKET}/")))
        trajectories = recording.read_trajectories(mcap)
        assert len(trajectories) >= 2 and all(len(s) > 10 for s in trajectories.values())

    # The report over that database names every scenario.
    report = tmp_path / "report.html"
    (tmp_path / "report-out").mkdir()
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            "from simtest_operator.cli.main import main; main()",
            "report",
            str(tmp_path / "report-out"),
            "--database",
            postgres_dsn,
            "--run",
            key,
            "--out",
            str(report),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    html = report.read_text(encoding="utf-8")
    assert all(name in html for name in names)


@pytest.mark.postgres
@pytest.mark.slow
@pytest.mark.timeout(900)
def test_a_database_that_is_down_costs_the_rows_not_the_verdicts(
    real_operator: support.OperatorProcess,
    cluster: support.Cluster,
    pod_host: str,
    tmp_path: Path,
) -> None:
    names = (FAILING, PASSING[0])
    create_secret(
        cluster, "results-db", {"dsn": f"postgresql://simtest@{pod_host}:{free_port()}/none"}
    )
    cluster.create(results_campaign(tmp_path, "dbdown", names, database="results-db"))
    status = cluster.wait_complete("dbdown", timeout=600, alive=real_operator.alive)
    batches = {b["metadata"]["name"] for b in cluster.items("scenariobatches")}

    def warnings() -> list[Any] | None:
        events = cluster.core.list_namespaced_event(cluster.namespace).items
        found = [
            e
            for e in events
            if e.reason == "ResultsNotStored"
            and e.type == "Warning"
            and e.involved_object.kind == "ScenarioBatch"
        ]
        return found if len(found) >= len(names) else None

    events = wait_for("ResultsNotStored events", warnings, timeout=60)
    found = cluster.results("dbdown")
    _check_verdicts(found, names)
    assert status["phase"] == "Failed" and status["failed"] == 1 and status["passed"] == 1
    assert all(r["resultsStored"] is False for r in found.values()), found
    assert {e.involved_object.name for e in events} <= batches
    messages = " ".join(e.message for e in events)
    assert all(name in messages for name in names), messages


def test_a_missing_dsn_secret_is_a_container_config_error(
    real_operator: support.OperatorProcess,
    cluster: support.Cluster,
    tmp_path: Path,
) -> None:
    cluster.create(results_campaign(tmp_path, "nosecret", [PASSING[0]], database="no-such-secret"))
    status = cluster.wait_complete("nosecret", timeout=180, alive=real_operator.alive)
    found = cluster.results("nosecret")
    result = found[PASSING[0]]
    assert result["verdict"] == "Error"
    assert "CreateContainerConfigError" in result["reason"]
    # The kubelet's own words, passed through: "secret ... not found" once its secret cache has
    # looked, or "failed to sync secret cache" when the watch for a secret that does not exist
    # times out first (seen on a loaded node); either names why the container cannot start.
    assert (
        'secret "no-such-secret" not found' in result["reason"]
        or "failed to sync secret cache" in result["reason"]
    ), result["reason"]
    assert status["phase"] == "Error"
