"""The results store contract: what the runner, the operator and the report need from a database.

Split like helm's storage driver into a writing side (:class:`ResultSink`: the local executor and
the operator record a campaign as it runs) and a reading side (:class:`ResultSource`: reports and
comparisons), combined in :class:`Store`. Two implementations share one schema:
:class:`~simtest_operator.results.sqlite.SqliteStore` (default, one file in the output folder) and
:class:`~simtest_operator.results.postgres.PostgresStore` (a DSN from a Secret);
:func:`simtest_operator.results.opening.open_store` picks one from a path or DSN.

Guarantees every implementation keeps:

* each call is one transaction: a run killed at any moment leaves whole rows, never an attempt
  without its metrics;
* :meth:`ResultSink.add_outcome` is idempotent per (run, scenario, attempt): recording the same
  attempt again replaces it, so a resumed run or a re-delivered pod result never duplicates;
* :meth:`ResultSink.begin_campaign` with an existing ``run_key`` resumes that run.
"""

from __future__ import annotations

import datetime
from collections.abc import Mapping, Sequence
from types import TracebackType
from typing import Protocol, Self

from simtest_operator.results import comparing, records
from simtest_operator.results.evaluationstore import EvaluationStore
from simtest_operator.verdicts import ScenarioOutcome


class ResultSink(Protocol):
    """Writing side: record a campaign run while it executes."""

    def begin_campaign(
        self,
        campaign: records.CampaignInfo,
        *,
        scenarios: Sequence[records.ScenarioInfo] = (),
        run_key: records.RunKey | None = None,
    ) -> records.RunKey:
        """Record a run's start and its frozen scenario list; returns the run's key.

        Without ``run_key`` the key is derived from namespace, name, start time and manifest
        digest (stable, so calling twice with the same info resumes). With an existing
        ``run_key`` the run is resumed: its record is kept and new scenarios are appended.
        """
        ...

    def add_outcome(
        self,
        run_key: records.RunKey,
        scenario: records.ScenarioInfo,
        outcome: ScenarioOutcome,
        *,
        content_hashes: Mapping[str, str] | None = None,
        recorded_at: datetime.datetime | None = None,
    ) -> None:
        """Record one attempt (``outcome.attempts`` is its number) with its metrics, atomically.

        ``content_hashes`` defaults to ``{"scenario": scenario.sha256}``; ``recorded_at`` to the
        store's clock. Raises :class:`~simtest_operator.errors.ResultsError` for an unknown run.
        """
        ...

    def add_versions(
        self,
        run_key: records.RunKey,
        additions: Mapping[tuple[str, int], Mapping[str, str]],
    ) -> None:
        """Merge entries into the ``versions`` of stored attempts, keyed (scenario id, attempt):
        what a writer other than the attempt's own learned about it (the operator: the SUT image
        the kubelet ran). Attempts without a row are skipped; merging twice is harmless.
        """
        ...

    def finish_campaign(
        self,
        run_key: records.RunKey,
        *,
        finished_at: datetime.datetime,
        phase: str,
        counts: Mapping[str, int] | None = None,
        info: records.CampaignInfo | None = None,
    ) -> None:
        """Mark a run finished with its final phase (``Succeeded``, ``Failed``, ``Cancelled``).

        ``counts`` stores the final counters; ``info`` (same campaign name) replaces what
        :meth:`begin_campaign` recorded about the run -- for a run first recorded by a simulator
        pod that knew only the campaign's name. Calling it again overwrites: it is idempotent for
        the same arguments.
        """
        ...


class ResultSource(Protocol):
    """Reading side: what reports and comparisons ask."""

    def campaigns(
        self, *, name: str | None = None, namespace: str | None = None, limit: int = 50
    ) -> tuple[records.CampaignRecord, ...]:
        """Campaign runs, newest first, optionally of one campaign."""
        ...

    def campaign(self, run_key: records.RunKey) -> records.CampaignRecord | None:
        """One campaign run, or ``None`` if the key is unknown."""
        ...

    def scenarios(self, run_key: records.RunKey) -> tuple[records.ScenarioInfo, ...]:
        """The run's frozen scenario list, in its original order."""
        ...

    def outcomes(
        self, run_key: records.RunKey, *, final_only: bool = True
    ) -> tuple[records.StoredOutcome, ...]:
        """Stored attempts of a run, by scenario id; only the last attempt of each by default."""
        ...

    def compare(self, base: records.RunKey, other: records.RunKey) -> comparing.Comparison:
        """New, fixed, regressed and still failing scenarios between two runs of this store."""
        ...


class Store(ResultSink, ResultSource, EvaluationStore, Protocol):
    """A results database: both sides plus closing; usable as a context manager."""

    @property
    def schema_version(self) -> int:
        """The highest applied migration."""
        ...

    def close(self) -> None:
        """Release the connection; the store cannot be used afterwards."""
        ...

    def __enter__(self) -> Self: ...

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None: ...
