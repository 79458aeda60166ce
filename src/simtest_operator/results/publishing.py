"""Publishing a run: load it from a store, then write the HTML report and the JUnit XML.

This is the action behind ``simtest report`` and the last step of ``simtest run``: the CLI only
parses options and prints the returned :class:`Published`. Stores are opened from a folder (its
``results.sqlite``) or a DSN; the run is the newest one unless a run key is given; the
comparison run comes from a second store (another output folder) or the same one.
"""

from __future__ import annotations

import dataclasses
import datetime
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

from simtest_operator.errors import ResultsError
from simtest_operator.results import (
    comparing,
    details,
    dsn,
    junit,
    opening,
    records,
    reporting,
    reportmodel,
    stores,
)

SearchSectionOf = Callable[
    [records.CampaignRecord, Sequence[records.StoredOutcome]], reportmodel.SearchSection | None
]
"""Builds a searching run's *Search* section from the stored run (None: it did not search)."""

REPORT_FILENAME = "report.html"
JUNIT_FILENAME = "junit.xml"
MAX_DETAILED = 500
"""Scenarios whose recordings are plotted (failing ones first); beyond that the report would
grow by megabytes for plots nobody opens."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RunRef:
    """Where to find a run: a store target (folder, file or DSN) and optionally its key."""

    target: str | Path
    run_key: records.RunKey | None = None
    base_dir: Path | None = None
    """Folder that relative artifact paths start from (default: the target if it is one)."""

    def artifacts_base(self) -> Path:
        """The folder relative artifact URIs are resolved against."""
        if self.base_dir is not None:
            return self.base_dir
        path = Path(self.target)
        return path if path.is_dir() else path.parent


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Published:
    """What was written and the headline figures."""

    run_key: records.RunKey
    report: Path | None
    junit: Path | None
    totals: Mapping[str, int]
    comparison: Mapping[comparing.Change, int] | None


def load_run(source: stores.ResultSource, run_key: records.RunKey | None = None) -> reportmodel.Run:
    """A run with every attempt and its frozen list; the newest run when no key is given."""
    if run_key is None:
        newest = source.campaigns(limit=1)
        if not newest:
            raise ResultsError("the results store holds no campaign run yet")
        campaign = newest[0]
    else:
        found = source.campaign(run_key)
        if found is None:
            raise ResultsError(f"no campaign run {run_key!r} in the results store")
        campaign = found
    return reportmodel.Run(
        campaign=campaign,
        outcomes=source.outcomes(campaign.run_key, final_only=False),
        scenarios=source.scenarios(campaign.run_key),
    )


def load_details(
    run: reportmodel.Run,
    base: Path,
    *,
    read_trajectories: details.TrajectoryReader | None = None,
    limit: int = MAX_DETAILED,
) -> dict[str, details.ScenarioDetails]:
    """Detail for up to ``limit`` scenarios, failing ones first."""
    final = comparing.final_outcomes(run.outcomes)
    order = sorted(final.values(), key=lambda s: (not records.is_failing(s.verdict),
                                                  s.scenario.scenario_id))  # fmt: skip
    loaded = {
        stored.scenario.scenario_id: details.load(stored, base, read_trajectories=read_trajectories)
        for stored in order[:limit]
    }
    skipped_note = (f"plots omitted: the report details the first {limit} scenarios "
                    "(failing first)",)  # fmt: skip
    for stored in order[limit:]:
        loaded[stored.scenario.scenario_id] = details.ScenarioDetails(notes=skipped_note)
    return loaded


def publish(
    run_ref: RunRef,
    *,
    now: datetime.datetime,
    report_path: Path | None = None,
    junit_path: Path | None = None,
    compare_with: RunRef | None = None,
    read_trajectories: details.TrajectoryReader | None = None,
    hostname: str = "",
    search: SearchSectionOf | reportmodel.SearchSection | None = None,
) -> Published:
    """Write the report and/or JUnit file of one run (paths ``None`` skip that output), with
    what its search found when it searched (the section, or how to build it from the run: the
    search engine sits above this layer)."""
    with opening.open_store(run_ref.target, create=False) as store:
        run = load_run(store, run_ref.run_key)
    comparison = None
    if compare_with is not None:
        with opening.open_store(compare_with.target, create=False) as other_store:
            base = load_run(other_store, compare_with.run_key)
        if base.campaign.run_key == run.campaign.run_key and base.outcomes == run.outcomes:
            raise ResultsError("the comparison run is the run itself; name another run or folder")
        comparison = comparing.compare(
            base.outcomes,
            run.outcomes,
            base_label=_label(compare_with, base),
            other_label=_label(run_ref, run),
        )
    written_report = written_junit = None
    if report_path is not None:
        view = reportmodel.build(
            run,
            generated_at=now,
            details_of=load_details(
                run, run_ref.artifacts_base(), read_trajectories=read_trajectories
            ),
            comparison=comparison,
            search=search(run.campaign, run.outcomes) if callable(search) else search,
        )
        document = reporting.render(view, source=dsn.describe(run_ref.target))
        written_report = reporting.write(report_path, document)
    if junit_path is not None:
        document = junit.render(run.campaign, run.outcomes, scenarios=run.scenarios,
                                hostname=hostname)  # fmt: skip
        written_junit = junit.write(junit_path, document)
    return Published(
        run_key=run.campaign.run_key,
        report=written_report,
        junit=written_junit,
        totals=reportmodel.verdict_totals(run),
        comparison=comparison.counts() if comparison else None,
    )


def _label(ref: RunRef, run: reportmodel.Run) -> str:
    where = dsn.describe(ref.target)
    return f"{run.campaign.run_key} ({where})"
