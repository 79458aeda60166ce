"""The operator's record of a campaign run in the results database (operator/recording_results.py).

Covers: the start recorded once the list is frozen (frozen list in order, not finished), the end
once the status is final (phase, counters, completionTime, description refreshed), nothing more
after that; the DSN read from the Secret the spec names; no database configured -> no Secret read;
a database that is down -> no exception, a retry after the backoff that then succeeds; a Secret
without the key -> a clear error in the log and a retry; the same against a real PostgreSQL, with
the Secret's DSN in every form libpq accepts (issue 12: a key/value DSN was taken for a SQLite
path); a Secret DSN that is down or ambiguous leaves no file and no password in the log; at the
end the SUT image the kubelet ran (the final results' ``sutImageId``) is merged into the rows the
pods wrote, the final attempt's only.
"""

from __future__ import annotations

import asyncio
import base64
import datetime
import logging
import socket
from pathlib import Path
from typing import Any

import pytest

from simtest_operator import results
from simtest_operator.operator import observed, recording_results
from simtest_operator.operator.client import NotFoundError
from simtest_operator.operator.scenariolists import StoredList
from simtest_operator.operator.status.records import ResultRecord
from simtest_operator.scenarios import FrozenList, PinnedScenario
from simtest_operator.verdicts import ScenarioOutcome, Verdict
from tests.results import dsnforms

T0 = datetime.datetime(2025, 3, 1, 12, 0, tzinfo=datetime.UTC)
CREATED = "2025-03-01T11:59:00Z"


class FakeSecrets:
    """Serves one Secret (or none) and counts reads."""

    def __init__(self, data: dict[str, str] | None) -> None:
        self.data = data
        self.reads = 0

    async def get(self, kind: Any, namespace: str | None, name: str) -> dict[str, Any]:
        self.reads += 1
        assert (kind, namespace, name) == ("secrets", "team-a", "results-db")
        if self.data is None:
            raise NotFoundError(404, "NotFound", f'secrets "{name}" not found')
        return {"data": {k: base64.b64encode(v.encode()).decode() for k, v in self.data.items()}}


class Clock:
    def __init__(self) -> None:
        self.now = T0

    def __call__(self) -> datetime.datetime:
        return self.now


def campaign(*, status: dict[str, Any] | None = None, database: bool = True) -> Any:
    spec: dict[str, Any] = {
        "scenarios": {"sources": [{"path": "scenarios"}]},
        "environment": {"sut": {"name": "idm-driver", "version": "2.0.0"}},
    }
    if database:
        spec["results"] = {"databaseSecretRef": {"name": "results-db", "key": "dsn"}}
    return observed.campaign_view(
        {
            "apiVersion": "simtest.dev/v1alpha1",
            "kind": "TestCampaign",
            "metadata": {
                "name": "nightly",
                "namespace": "team-a",
                "uid": "0b1c",
                "creationTimestamp": CREATED,
            },
            "spec": spec,
            "status": status or {},
        }
    )


FINAL = {
    "phase": "Failed",
    "completionTime": "2025-03-01T12:10:00Z",
    "total": 2,
    "queued": 0,
    "running": 0,
    "passed": 1,
    "failed": 1,
    "errored": 0,
    "timedOut": 0,
    "invalid": 0,
    "skipped": 0,
}


def stored() -> StoredList:
    return StoredList(
        frozen=FrozenList(
            campaign="nightly",
            scenarios=tuple(
                PinnedScenario(id=f"s{i}.xosc", source=f"file:///s/s{i}.xosc", sha256=f"{i:064x}")
                for i in (2, 1)
            ),
        ),
        batch_size=10,
    )


def _dead_dsn() -> str:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    return f"postgresql://nobody@127.0.0.1:{port}/none"


async def _observe(recorder: recording_results.CampaignRecorder, view: Any) -> None:
    recorder.observe(view, stored())
    await recorder.wait()


def _scenario_ids(store: results.Store, key: results.RunKey) -> list[str]:
    return [s.scenario_id for s in store.scenarios(key)]


def test_start_then_finish_are_recorded_once(tmp_path: Path) -> None:
    target = str(tmp_path / "results.sqlite")
    secrets, clock = FakeSecrets({"dsn": target}), Clock()
    recorder = recording_results.CampaignRecorder(secrets, clock=clock)
    running = campaign(status={"phase": "Running", "startTime": CREATED})
    key = recording_results.run_key(running)

    async def scenario() -> None:
        await _observe(recorder, running)
        with results.open_store(target) as store:
            record = store.campaign(key)
            assert record is not None and not record.finished
            assert record.info.namespace == "team-a"
            assert record.info.sut_version == "2.0.0"
            assert _scenario_ids(store, key) == ["s2.xosc", "s1.xosc"]  # frozen order
        await _observe(recorder, running)  # started already: nothing to do
        assert secrets.reads == 1
        await _observe(recorder, campaign(status=FINAL))
        assert recorder.finished
        await _observe(recorder, campaign(status=FINAL))
        assert secrets.reads == 2

    asyncio.run(scenario())
    with results.open_store(target) as store:
        record = store.campaign(key)
    assert record is not None
    assert record.phase == "Failed"
    assert record.finished_at == datetime.datetime(2025, 3, 1, 12, 10, tzinfo=datetime.UTC)
    assert record.counts["passed"] == 1 and record.counts["failed"] == 1
    assert record.info.started_at == datetime.datetime(2025, 3, 1, 11, 59, tzinfo=datetime.UTC)


def test_without_a_database_nothing_is_read() -> None:
    secrets = FakeSecrets({"dsn": "unused"})
    recorder = recording_results.CampaignRecorder(secrets, clock=Clock())
    asyncio.run(_observe(recorder, campaign(status=FINAL, database=False)))
    assert secrets.reads == 0
    assert not recorder.finished


def test_a_database_that_is_down_is_retried_after_a_backoff(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    dead = _dead_dsn()
    secrets, clock = FakeSecrets({"dsn": dead}), Clock()
    recorder = recording_results.CampaignRecorder(secrets, clock=clock)
    final = campaign(status=FINAL)

    async def scenario() -> None:
        with caplog.at_level(logging.WARNING):
            await _observe(recorder, final)
        assert not recorder.finished
        assert "cannot record the run" in caplog.text
        assert "nobody" not in caplog.text  # the DSN's user (and any password) stays out
        await _observe(recorder, final)  # within the backoff: no new attempt
        assert secrets.reads == 1
        secrets.data = {"dsn": str(tmp_path / "results.sqlite")}
        clock.now += datetime.timedelta(seconds=recording_results.FIRST_RETRY_SECONDS + 1)
        await _observe(recorder, final)
        assert recorder.finished

    asyncio.run(scenario())
    with results.open_store(tmp_path / "results.sqlite") as store:
        record = store.campaign(recording_results.run_key(final))
    assert record is not None and record.phase == "Failed"


def test_a_secret_without_the_key_is_reported(caplog: pytest.LogCaptureFixture) -> None:
    secrets, clock = FakeSecrets({"other": "x"}), Clock()
    recorder = recording_results.CampaignRecorder(secrets, clock=clock)
    with caplog.at_level(logging.WARNING):
        asyncio.run(_observe(recorder, campaign(status=FINAL)))
    assert "has no key 'dsn'" in caplog.text
    secrets.data = None
    clock.now += datetime.timedelta(hours=1)
    with caplog.at_level(logging.WARNING):
        asyncio.run(_observe(recorder, campaign(status=FINAL)))
    assert "not found" in caplog.text
    assert not recorder.finished


@pytest.mark.parametrize(
    "dsn",
    [f"host=127.0.0.1 port=1 password={dsnforms.PASSWORD} dbname=d",
     f"POSTGRESQL://u:{dsnforms.PASSWORD}@127.0.0.1:1/d",
     f"host=127.0.0.1 password={dsnforms.PASSWORD} dbname"],
)  # fmt: skip
def test_a_secret_dsn_in_any_form_leaves_no_file_and_no_password(
    dsn: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.chdir(tmp_path)
    recorder = recording_results.CampaignRecorder(FakeSecrets({"dsn": dsn}), clock=Clock())
    with caplog.at_level(logging.DEBUG):
        asyncio.run(_observe(recorder, campaign(status=FINAL)))
    assert not recorder.finished
    assert "cannot record the run" in caplog.text
    assert dsnforms.PASSWORD not in caplog.text
    assert list(tmp_path.iterdir()) == []


@pytest.mark.postgres
@pytest.mark.parametrize("form", ["as-given", *dsnforms.forms("host=h port=1 user=u dbname=d")])
def test_finish_into_postgresql(postgres_dsn: str, form: str) -> None:
    dsn = postgres_dsn if form == "as-given" else dsnforms.forms(postgres_dsn)[form]
    recorder = recording_results.CampaignRecorder(FakeSecrets({"dsn": dsn}), clock=Clock())
    final = campaign(status=FINAL)
    asyncio.run(_observe(recorder, final))
    with results.open_store(postgres_dsn) as store:
        record = store.campaign(recording_results.run_key(final))
        listed = _scenario_ids(store, recording_results.run_key(final))
    assert record is not None and record.finished and record.counts["total"] == 2
    assert listed == ["s2.xosc", "s1.xosc"]


SUT_IMAGE = "ghcr.io/simtest-dev/simtest-sut-go@sha256:" + "5e" * 32
BARE_IMAGE = "sha256:" + "c0" * 32


def _batch(*records: ResultRecord) -> observed.BatchView:
    return observed.batch_view(
        {
            "metadata": {"name": "nightly-b00000", "namespace": "team-a"},
            "spec": {"campaign": "nightly", "index": 0, "scenarios": []},
            "status": {"results": [r.to_wire() for r in records]},
        }
    )


def test_the_finished_campaign_merges_the_image_into_the_pods_rows(tmp_path: Path) -> None:
    target = str(tmp_path / "results.sqlite")
    final = campaign(status=FINAL)
    key = recording_results.run_key(final)
    now = datetime.datetime(2025, 3, 1, 12, 5, tzinfo=datetime.UTC)
    (second, first) = recording_results.scenario_infos(stored())
    pod_versions = {"sut.reported": "simtest-sut-go 1.0.0", "sut.imageID": "unknown"}
    with results.open_store(target) as store:  # what the pods wrote (s1 took two attempts)
        for info, attempt in ((first, 1), (first, 2), (second, 1)):
            outcome = ScenarioOutcome(
                scenario_id=info.scenario_id,
                verdict=Verdict.ERROR if attempt == 1 and info is first else Verdict.PASSED,
                attempts=attempt,
                versions=pod_versions,
            )
            results.record_pod_attempt(
                store, key, campaign="nightly", scenario=info, outcome=outcome, now=now
            )
    batch = _batch(
        ResultRecord(id="s1.xosc", verdict=Verdict.PASSED, attempts=2, sut_image_id=BARE_IMAGE),
        ResultRecord(id="s2.xosc", verdict=Verdict.PASSED, sut_image_id=SUT_IMAGE),
    )
    recorder = recording_results.CampaignRecorder(FakeSecrets({"dsn": target}), clock=Clock())

    async def finish() -> None:
        recorder.observe(final, stored(), [batch])
        await recorder.wait()

    asyncio.run(finish())
    assert recorder.finished
    with results.open_store(target) as store:
        rows = {
            (s.scenario.scenario_id, s.outcome.attempts): s.outcome.versions
            for s in store.outcomes(key, final_only=False)
        }
    assert rows[("s1.xosc", 2)] == {**pod_versions, "sut.imageID": BARE_IMAGE}
    assert rows[("s2.xosc", 1)] == {**pod_versions, "sut.imageID": SUT_IMAGE}
    assert rows[("s1.xosc", 1)] == pod_versions  # an earlier attempt's pod is not the final one's


def test_batches_without_images_add_nothing() -> None:
    batch = _batch(ResultRecord(id="s1.xosc", verdict=Verdict.PASSED))
    assert recording_results.sut_images([batch]) == {}
