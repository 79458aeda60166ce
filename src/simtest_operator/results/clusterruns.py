"""Campaign runs on a cluster: one run record written by many pods and finished by the operator.

A local ``simtest run`` is one process that begins, fills and finishes its record. On a cluster
the writers are spread out: every simulator pod records its own attempts the moment it has them,
and the operator, which alone knows when the whole campaign is over, marks the run finished with
its phase and counters. They meet on the run key, which both derive from the TestCampaign object
(:func:`cluster_run_key`), so nothing has to be passed back and forth and a restarted operator or
a retried pod lands on the same record.

Either side may be first: the operator records the start when it has frozen the list, but a pod
whose result arrives while the database was unreachable for the operator creates the record
itself from what it knows (the campaign's name), and the operator fills in the rest at the end.
Every function here is idempotent; they go through the one :class:`~.stores.Store` code path
``simtest run`` uses.
"""

from __future__ import annotations

import dataclasses
import datetime
import hashlib
import re
from collections.abc import Mapping, Sequence

from simtest_operator.results import records, stores
from simtest_operator.verdicts import ScenarioOutcome

_KEY_TIME = re.compile(r"-(\d{8}T\d{6}Z)-[0-9a-f]{8}$")


def cluster_run_key(
    *, namespace: str, name: str, uid: str, created: datetime.datetime | None
) -> records.RunKey:
    """``<name>-<UTC creation>-<8 hex of namespace/name/uid>``: one key per TestCampaign object.

    The uid makes a campaign deleted and re-applied under the same name a new run (CI does that
    every night), while the operator, its restarts and every pod of the campaign agree on it.
    """
    digest = hashlib.sha256(f"{namespace}/{name}#{uid}".encode()).hexdigest()[:8]
    if created is None:
        return records.RunKey(f"{name}-{digest}")
    when = created.astimezone(datetime.UTC)
    return records.RunKey(f"{name}-{when:%Y%m%dT%H%M%SZ}-{digest}")


def key_time(key: records.RunKey) -> datetime.datetime | None:
    """The UTC time embedded in a key of :func:`cluster_run_key` or ``derive_run_key``."""
    match = _KEY_TIME.search(key)
    if match is None:
        return None
    return datetime.datetime.strptime(match.group(1), "%Y%m%dT%H%M%SZ").replace(tzinfo=datetime.UTC)


def start_campaign_run(
    store: stores.Store,
    key: records.RunKey,
    *,
    info: records.CampaignInfo,
    scenarios: Sequence[records.ScenarioInfo] = (),
) -> None:
    """Record the run and its frozen list (in order); a no-op for what is recorded already."""
    store.begin_campaign(info, scenarios=scenarios, run_key=key)


def record_pod_attempt(
    store: stores.Store,
    key: records.RunKey,
    *,
    campaign: str,
    scenario: records.ScenarioInfo,
    outcome: ScenarioOutcome,
    content_hashes: Mapping[str, str] | None = None,
    now: datetime.datetime,
    sut_name: str = "",
    sut_version: str = "",
) -> None:
    """Record one attempt of a pod; creates a provisional run record when none exists yet.

    Idempotent per (key, scenario, ``outcome.attempts``): a retried pod or a runner that writes
    twice replaces its row. The provisional record carries the campaign's name and the time in
    the key (else ``now``); the operator completes it when the campaign finishes.
    """
    store.begin_campaign(
        records.CampaignInfo(
            name=campaign,
            started_at=key_time(key) or now,
            sut_name=sut_name,
            sut_version=sut_version,
        ),
        run_key=key,
    )
    store.add_outcome(key, scenario, outcome, content_hashes=content_hashes, recorded_at=now)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Finish:
    """How a campaign ended, as the operator saw it."""

    phase: str
    """Final phase: ``Succeeded``, ``Failed``, ``Error`` or ``Cancelled``."""
    counts: Mapping[str, int]
    """Final counters of the campaign status (``total``, ``passed``, ``failed``, ...)."""
    finished_at: datetime.datetime
    """The campaign's ``completionTime`` (stable, so finishing twice writes the same row)."""


def finish_campaign_run(
    store: stores.Store,
    key: records.RunKey,
    *,
    info: records.CampaignInfo,
    finish: Finish,
    scenarios: Sequence[records.ScenarioInfo] = (),
    versions: Mapping[tuple[str, int], Mapping[str, str]] | None = None,
) -> records.CampaignRecord:
    """Create the run record if needed, complete its description and mark it finished.

    ``scenarios`` (the frozen list) are appended to the run's list where missing, so a report
    names scenarios that never got a row. ``versions`` ((scenario id, attempt) -> entries) are
    merged into the attempts' rows the pods wrote: what only the operator saw (the SUT image the
    kubelet ran). Idempotent: calling it again with the same values leaves the same record.
    Returns the stored record.
    """
    store.begin_campaign(info, scenarios=scenarios, run_key=key)
    if versions:
        store.add_versions(key, versions)
    store.finish_campaign(
        key,
        finished_at=finish.finished_at,
        phase=finish.phase,
        counts=finish.counts,
        info=info,
    )
    record = store.campaign(key)
    assert record is not None  # begun above, in the same store
    return record
