"""Records: the values the results store takes and returns.

They describe a campaign run, the scenarios it ran and one stored attempt per scenario, in the
vocabulary of :mod:`simtest_operator.verdicts`. Both store implementations (SQLite, PostgreSQL),
the JUnit writer and the HTML report work on these and nothing else, so a report can be built from
either database, or from plain values in a test.
"""

from __future__ import annotations

import dataclasses
import datetime
import hashlib
from collections.abc import Mapping
from typing import Any, NewType

from simtest_operator.verdicts import ScenarioOutcome, Verdict

RunKey = NewType("RunKey", str)
"""Identifies one run of one campaign in a store, e.g. ``smoke-20250101T120000Z-3f2a9c1d``."""

UNCATEGORIZED = "uncategorized"
"""Category of a scenario whose file header names none (JUnit classname, report grouping)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class CampaignInfo:
    """What is known about a campaign run when it starts."""

    name: str
    """``metadata.name`` of the TestCampaign."""
    namespace: str = ""
    """Kubernetes namespace; empty for a local ``simtest run``."""
    manifest_sha256: str = ""
    """Digest of the manifest as read, so a result can be traced to the exact spec."""
    started_at: datetime.datetime
    """Timezone-aware start time (the caller's clock; the store never reads one)."""
    sut_name: str = ""
    sut_version: str = ""
    simulator_version: str = ""
    settings: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    """JSON-compatible execution settings worth keeping (parallelism, step length, seed, ...)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class CampaignRecord:
    """A campaign run as stored."""

    run_key: RunKey
    info: CampaignInfo
    finished_at: datetime.datetime | None = None
    """``None`` while running, or when the run was killed before it finished."""
    phase: str = ""
    """Final phase given to :meth:`Store.finish_campaign` (e.g. ``Succeeded``, ``Cancelled``)."""
    counts: Mapping[str, int] = dataclasses.field(default_factory=dict)
    """Final counters given to :meth:`Store.finish_campaign` (``total``, ``passed``, ...); empty
    when none were given (a local run derives them from its rows)."""

    @property
    def finished(self) -> bool:
        """Whether :meth:`Store.finish_campaign` was called for this run."""
        return self.finished_at is not None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ScenarioInfo:
    """One entry of the frozen scenario list, with what the report groups by."""

    scenario_id: str
    source: str = ""
    """Where the file came from (resolved source URI + path)."""
    sha256: str
    """Digest of the scenario file; the same id with another digest is a changed scenario."""
    tags: tuple[str, ...] = ()
    category: str = UNCATEGORIZED
    """Scenario type, e.g. ``cut-in``; the JUnit classname."""
    road: str = ""
    """Road network (OpenDRIVE file name) the scenario runs on."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class StoredOutcome:
    """One attempt at one scenario, as stored: the outcome plus the scenario it belongs to."""

    scenario: ScenarioInfo
    outcome: ScenarioOutcome
    """``outcome.attempts`` is the attempt number of this row."""
    content_hashes: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """Digests of the inputs and outputs (``scenario``, ``road``, ``recording``, ...)."""
    recorded_at: datetime.datetime | None = None

    @property
    def verdict(self) -> Verdict:
        """Shortcut for ``outcome.verdict``."""
        return self.outcome.verdict


def is_failing(verdict: Verdict) -> bool:
    """Whether a verdict counts against the campaign (everything but Passed and Skipped)."""
    return verdict not in (Verdict.PASSED, Verdict.SKIPPED)


def derive_run_key(campaign: CampaignInfo) -> RunKey:
    """A readable, stable key: ``<name>-<UTC start>-<8 hex of namespace/name/start/manifest>``.

    Stable so that beginning the same run twice (a restarted operator) resumes instead of forking.
    """
    started = campaign.started_at.astimezone(datetime.UTC)
    identity = (
        f"{campaign.namespace}/{campaign.name}@{started.isoformat()}#{campaign.manifest_sha256}"
    )
    digest = hashlib.sha256(identity.encode()).hexdigest()[:8]
    return RunKey(f"{campaign.name}-{started:%Y%m%dT%H%M%SZ}-{digest}")
