"""Recording a campaign run in the results database: its start once resolved, its end once complete.

The simulator pods write one row per attempt themselves (:mod:`simtest_operator.runner.delivering`);
only the operator knows the frozen list up front and when the whole campaign is over, so it records
those two facts -- through :mod:`simtest_operator.results.clusterruns`, the one code path every
writer uses. The DSN is read from the Secret named by ``spec.results.databaseSecretRef`` at each
attempt (never cached, never logged).

A database that is slow or down must not slow the campaign: :meth:`CampaignRecorder.observe`
returns at once and does the work in a background task (the database calls in a thread), one at a
time per campaign, retried with backoff. The campaign's status stays the source of truth; the
database record is completed whenever it is reachable again, and recording twice is harmless.
"""

from __future__ import annotations

import asyncio
import base64
import datetime
import logging
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any, Protocol

from simtest_operator import provenance, results
from simtest_operator.errors import ResultsError, SimtestError
from simtest_operator.operator.observed import BatchView, CampaignView
from simtest_operator.operator.scenariolists import StoredList
from simtest_operator.operator.status import reading
from simtest_operator.render import documents
from simtest_operator.scenarios.pinned import PinnedScenario

log = logging.getLogger(__name__)

FIRST_RETRY_SECONDS = 10.0
MAX_RETRY_SECONDS = 900.0
CONNECT_TIMEOUT_SECONDS = 5

OpenStore = Callable[[str], results.Store]


class SecretReader(Protocol):
    """The part of :class:`~simtest_operator.operator.client.Client` the recorder uses."""

    async def get(self, kind: Any, namespace: str | None, name: str) -> dict[str, Any]: ...


def _open_store(dsn: str) -> results.Store:
    return results.open_store(dsn, connect_timeout=CONNECT_TIMEOUT_SECONDS)


def run_key(campaign: CampaignView) -> results.RunKey:
    """The results run key of a TestCampaign object; the same one its pods are given."""
    return results.cluster_run_key(
        namespace=campaign.namespace,
        name=campaign.name,
        uid=campaign.uid,
        created=campaign.created,
    )


SearchRecord = tuple[Sequence[PinnedScenario], Mapping[str, Any]]
"""A finished search's frozen list (its proposals) and its record (``settings.search``)."""


def campaign_info(
    campaign: CampaignView, *, now: datetime.datetime, search: Mapping[str, Any] | None = None
) -> results.CampaignInfo:
    """What the results record says about the campaign (its creation counts as its start)."""
    spec = campaign.spec
    assert spec is not None
    digest = documents.content_hash(spec.to_wire())
    environment = spec.environment
    return results.CampaignInfo(
        name=campaign.name,
        namespace=campaign.namespace,
        manifest_sha256=digest,
        started_at=campaign.created or now,
        sut_name=environment.sut.name,
        sut_version=environment.sut.version,
        simulator_version=environment.simulator.image,
        settings={
            **spec.execution.to_wire(),
            "seed": environment.simulator.seed,
            **({"search": search} if search is not None else {}),
        },
    )


def finish_of(campaign: CampaignView) -> results.Finish | None:
    """The end of a campaign as its status tells it, or None while it is not over."""
    status = campaign.status
    finished_at = status.completion_time
    if not status.phase.finished or finished_at is None:
        return None
    return results.Finish(
        phase=status.phase.value, counts=reading.counts(status), finished_at=finished_at
    )


def scenario_infos(
    stored: StoredList | None, search: SearchRecord | None = None, *, searching: bool = False
) -> list[results.ScenarioInfo]:
    """The frozen list as the store's scenario records (no header labels: the pods add them); a
    search's list is its proposals, known once it is over (the pods add theirs as they run)."""
    if stored is None:
        return []
    listed: Sequence[PinnedScenario] = stored.frozen.scenarios
    if searching:
        listed = search[0] if search is not None else ()
    return [
        results.ScenarioInfo(scenario_id=s.id, sha256=s.sha256, source=s.source) for s in listed
    ]


def sut_images(batches: Iterable[BatchView]) -> dict[tuple[str, int], dict[str, str]]:
    """(scenario id, attempt) -> the versions entry naming the SUT image the kubelet ran, for
    every final result that has one (the pod's own row could only say ``unknown``)."""
    return {
        (r.id, r.attempts): {provenance.SUT_IMAGE_ID: r.sut_image_id}
        for batch in batches
        for r in batch.results
        if r.sut_image_id
    }


class CampaignRecorder:
    """Records one campaign's run; owned by its campaign loop."""

    def __init__(
        self,
        client: SecretReader,
        *,
        clock: Callable[[], datetime.datetime],
        open_store: OpenStore = _open_store,
    ) -> None:
        self._client = client
        self._clock = clock
        self._open_store = open_store
        self._task: asyncio.Task[None] | None = None
        self._started = False
        self._finished = False
        self._retry_at: datetime.datetime | None = None
        self._delay = FIRST_RETRY_SECONDS

    @property
    def finished(self) -> bool:
        """Whether the campaign's end is recorded."""
        return self._finished

    def observe(
        self,
        campaign: CampaignView,
        stored: StoredList | None,
        batches: Iterable[BatchView] = (),
        *,
        search: SearchRecord | None = None,
    ) -> None:
        """After a reconcile step: start recording what is due; never blocks, never raises.
        ``batches`` give the final results whose SUT image goes into the pods' rows at the end;
        ``search``, a finished search's proposals and record."""
        spec = campaign.spec
        if spec is None or spec.results.database_secret_ref is None or self._finished:
            return
        if self._task is not None and not self._task.done():
            return
        if self._retry_at is not None and self._clock() < self._retry_at:
            return
        finish = finish_of(campaign)
        if finish is None and (self._started or stored is None):
            return
        versions = sut_images(batches) if finish is not None else {}
        self._task = asyncio.get_running_loop().create_task(
            self._record(campaign, stored, finish, versions, search),
            name=f"results record {campaign.namespace}/{campaign.name}",
        )

    async def wait(self) -> None:
        """Wait for the recording in progress, if any (tests, shutdown)."""
        if self._task is not None:
            await asyncio.shield(self._task)

    async def _record(
        self,
        campaign: CampaignView,
        stored: StoredList | None,
        finish: results.Finish | None,
        versions: Mapping[tuple[str, int], Mapping[str, str]],
        search: SearchRecord | None,
    ) -> None:
        where = f"{campaign.namespace}/{campaign.name}"
        try:
            dsn = await self._dsn(campaign)
            record = search[1] if search is not None and finish is not None else None
            info = campaign_info(campaign, now=self._clock(), search=record)
            key = run_key(campaign)
            infos = scenario_infos(
                stored,
                search,
                searching=campaign.spec is not None and campaign.spec.search is not None,
            )
            await asyncio.to_thread(self._write, dsn, key, info, infos, finish, versions)
        except Exception as exc:  # a record is never worth a crashed task
            if not isinstance(exc, SimtestError | OSError):
                log.exception("%s: unexpected error while recording the run", where)
            self._retry_at = self._clock() + datetime.timedelta(seconds=self._delay)
            log.warning(
                "%s: cannot record the run in the results database (%s); retrying in %.0fs",
                where,
                exc,
                self._delay,
            )
            self._delay = min(self._delay * 2, MAX_RETRY_SECONDS)
            return
        self._retry_at = None
        self._delay = FIRST_RETRY_SECONDS
        self._started = True
        if finish is not None:
            self._finished = True
            log.info("%s: results run %s finished as %s", where, key, finish.phase)

    async def _dsn(self, campaign: CampaignView) -> str:
        assert campaign.spec is not None
        ref = campaign.spec.results.database_secret_ref
        assert ref is not None
        body = await self._client.get("secrets", campaign.namespace, ref.name)
        return decode_secret(body, name=ref.name, key=ref.key)

    def _write(
        self,
        dsn: str,
        key: results.RunKey,
        info: results.CampaignInfo,
        infos: list[results.ScenarioInfo],
        finish: results.Finish | None,
        versions: Mapping[tuple[str, int], Mapping[str, str]],
    ) -> None:
        with self._open_store(dsn) as store:
            if finish is None:
                results.start_campaign_run(store, key, info=info, scenarios=infos)
            else:
                results.finish_campaign_run(
                    store, key, info=info, finish=finish, scenarios=infos, versions=versions
                )


def decode_secret(body: Mapping[str, Any], *, name: str, key: str) -> str:
    """One key of a Secret body, decoded; a clear error when it is missing."""
    raw = (body.get("data") or {}).get(key)
    if raw is None:
        raise ResultsError(
            f"Secret {name!r} has no key {key!r}; add the DSN there or fix "
            "spec.results.databaseSecretRef"
        )
    try:
        return base64.b64decode(raw, validate=True).decode("utf-8").strip()
    except ValueError as exc:
        raise ResultsError(f"Secret {name!r} key {key!r} is not base64 UTF-8 text") from exc
