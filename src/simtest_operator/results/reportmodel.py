"""The report's view model: one run's outcomes turned into what each page section shows.

Pure: records, details and an optional comparison in, plain values out (counts, rows, SVG
markup). The template only lays them out, so every figure a reader sees is computed -- and
tested -- here.
"""

from __future__ import annotations

import dataclasses
import datetime
import math
import re
from collections.abc import Callable, Iterable, Mapping, Sequence

from simtest_operator.results import comparing, details, plots, records

NOT_RUN = "Not run"
VERDICT_ORDER = tuple(plots.VERDICT_COLOURS)
"""Passed, Failed, Timeout, Error, Invalid, Skipped, Not run: the order of every count."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Run:
    """One campaign run as loaded from a store."""

    campaign: records.CampaignRecord
    outcomes: tuple[records.StoredOutcome, ...]
    """Every attempt (the last per scenario is the verdict)."""
    scenarios: tuple[records.ScenarioInfo, ...] = ()
    """The frozen list, including scenarios that never ran."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class GroupRow:
    """Verdict counts of the scenarios sharing a tag, road network or category."""

    label: str
    counts: Mapping[str, int]
    total: int
    passed: int
    failing: int

    @property
    def ran(self) -> int:
        """Scenarios that reached a verdict other than Skipped."""
        return self.total - self.counts.get("Skipped", 0) - self.counts.get(NOT_RUN, 0)

    @property
    def pass_rate(self) -> float:
        """Passed over scenarios that ran (0 when none did)."""
        return self.passed / self.ran if self.ran else 0.0


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ScenarioView:
    """One scenario in the list and in its developer view."""

    anchor: str
    scenario: records.ScenarioInfo
    verdict: str
    reason: str
    attempts: int
    metrics: tuple[tuple[str, str], ...]
    simulated_seconds: float
    wall_seconds: float
    artifacts: tuple[tuple[str, str], ...]
    versions: tuple[tuple[str, str], ...]
    """(label, value) of the scenario's reproducibility record: versions and digests."""
    ignored_elements: tuple[str, ...]
    history: tuple[tuple[int, str, str], ...]
    """Earlier attempts: (attempt, verdict, reason)."""
    trajectory_svg: str
    timeline_svgs: tuple[str, ...]
    notes: tuple[str, ...]
    change: str = ""

    @property
    def failing(self) -> bool:
        """Whether the verdict counts against the campaign."""
        return self.verdict not in ("Passed", "Skipped", NOT_RUN)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Provenance:
    """What the header names of the run's reproducibility record, so a reader can rerun it."""

    simulator: str = ""
    """The campaign's simulator: SUMO and engine versions for ``simtest run``, the runner image
    for a campaign recorded from the cluster."""
    engine: str = ""
    """What the scenarios' own records name as simulator, when it adds to ``simulator`` (a
    cluster campaign names its image; its pods record the SUMO version)."""
    lock: str = ""
    """Digest of the ``uv.lock`` the run was installed from; several, joined, if scenarios
    differ."""

    @property
    def short_lock(self) -> str:
        """The lock digest(s) cut to 12 hex digits: enough to tell locks apart at a glance."""
        return " / ".join(_short_digest(part) for part in self.lock.split(" / ") if part)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SearchSection:
    """What a search (``spec.search``) found, prepared by the caller that ran it: the search
    engine sits above the results layer, so the report takes its findings as ready text and
    pictures."""

    facts: tuple[tuple[str, str], ...]
    """(label, value): budget, strategy, failures, regions, boundary, best objective."""
    critical: tuple[tuple[str, str, str], ...] = ()
    """(scenario id, parameter values, verdict) of the most critical concrete scenarios."""
    plots: tuple[tuple[str, str], ...] = ()
    """(caption, ``data:`` URI of a PNG or SVG): pass/fail per parameter pair with the boundary."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Report:
    """Everything the template renders."""

    campaign: records.CampaignRecord
    generated_at: datetime.datetime
    totals: Mapping[str, int]
    total: int
    category_chart: str
    coverage: tuple[tuple[str, tuple[GroupRow, ...]], ...]
    scenarios: tuple[ScenarioView, ...]
    comparison: comparing.Comparison | None
    provenance: Provenance = dataclasses.field(default_factory=Provenance)
    search: SearchSection | None = None
    verdict_colours: Mapping[str, str] = dataclasses.field(
        default_factory=lambda: dict(plots.VERDICT_COLOURS)
    )

    @property
    def duration_seconds(self) -> float | None:
        """Wall time of the campaign, if it finished."""
        finished = self.campaign.finished_at
        return (finished - self.campaign.info.started_at).total_seconds() if finished else None


def anchor(scenario_id: str) -> str:
    """An HTML id for a scenario, stable across runs (so comparison links work)."""
    return "s-" + re.sub(r"[^A-Za-z0-9_-]+", "-", scenario_id).strip("-")


def build(
    run: Run,
    *,
    generated_at: datetime.datetime,
    details_of: Mapping[str, details.ScenarioDetails] | None = None,
    comparison: comparing.Comparison | None = None,
    search: SearchSection | None = None,
) -> Report:
    """The view model of one run (with an optional comparison against another, and what its
    search found)."""
    final = comparing.final_outcomes(run.outcomes)
    attempts: dict[str, list[records.StoredOutcome]] = {}
    for stored in run.outcomes:
        attempts.setdefault(stored.scenario.scenario_id, []).append(stored)
    listed = {s.scenario_id: s for s in run.scenarios}
    infos = {**listed, **{key: stored.scenario for key, stored in final.items()}}
    verdict_of = {key: final[key].verdict.value if key in final else NOT_RUN for key in infos}
    changes = {c.scenario_id: c.change.value for c in comparison.changes} if comparison else {}
    views = [
        _scenario_view(
            infos[key],
            final.get(key),
            sorted(attempts.get(key, []), key=lambda s: s.outcome.attempts)[:-1],
            (details_of or {}).get(key, details.ScenarioDetails()),
            changes.get(key, ""),
        )
        for key in infos
    ]
    views.sort(key=lambda v: (not v.failing, v.verdict == NOT_RUN, v.scenario.scenario_id))
    return Report(
        campaign=run.campaign,
        generated_at=generated_at,
        totals=_count(verdict_of.values()),
        total=len(infos),
        category_chart=plots.stacked_bars(
            [(row.label, row.counts) for row in _group(infos, verdict_of, _by_category)]
        ),
        coverage=(
            ("Scenario type", _group(infos, verdict_of, _by_category)),
            ("Road network", _group(infos, verdict_of, lambda s: (s.road or "(unknown)",))),
            ("Tag", _group(infos, verdict_of, lambda s: s.tags or ("(untagged)",))),
        ),
        scenarios=tuple(views),
        comparison=comparison,
        provenance=_provenance(run.campaign.info, [s.outcome.versions for s in final.values()]),
        search=search,
    )


def verdict_totals(run: Run) -> dict[str, int]:
    """How many scenarios of the run (frozen list included) ended with each verdict."""
    final = comparing.final_outcomes(run.outcomes)
    ids = {s.scenario_id for s in run.scenarios} | final.keys()
    return _count(final[key].verdict.value if key in final else NOT_RUN for key in ids)


def _provenance(info: records.CampaignInfo, recorded: Sequence[Mapping[str, str]]) -> Provenance:
    """The campaign row's record first (``simtest run`` stores it), else what the scenarios'
    outcomes agree on (a cluster campaign's pods record theirs per scenario)."""
    campaign = info.settings.get("versions")
    campaign = campaign if isinstance(campaign, Mapping) else {}
    engine = _agreed(v.get("simulator", "") for v in recorded)
    simulator = info.simulator_version or engine
    lock = str(campaign.get("lock", "")) or _agreed(v.get("lock", "") for v in recorded)
    return Provenance(simulator=simulator, engine=engine if engine != simulator else "", lock=lock)


def _agreed(values: Iterable[str]) -> str:
    return " / ".join(sorted({value for value in values if value}))


def _short_digest(value: str) -> str:
    algorithm, _, digest = value.partition(":")
    return f"{algorithm}:{digest[:12]}" if digest and algorithm.isalnum() else value


_LABELS = {
    "sut.reported": "SUT as it reported itself",
    "sut.configHash": "SUT config hash",
    "sut.image": "SUT image",
    "sut.imageID": "SUT image digest",
    "sut.launch": "SUT launched as",
}
"""Labels of the entries that name the SUT (:mod:`simtest_operator.sut.runs`)."""


def _version_label(name: str) -> str:
    if name in _LABELS:
        return _LABELS[name]
    return f"{name} digest" if name in ("lock", "installed") else f"{name} version"


def _by_category(scenario: records.ScenarioInfo) -> tuple[str, ...]:
    return (scenario.category or records.UNCATEGORIZED,)


def _count(verdicts: Iterable[str]) -> dict[str, int]:
    counts = dict.fromkeys(VERDICT_ORDER, 0)
    for verdict in verdicts:
        counts[verdict] += 1
    return counts


def _group(
    infos: Mapping[str, records.ScenarioInfo],
    verdict_of: Mapping[str, str],
    keys_of: Callable[[records.ScenarioInfo], Sequence[str]],
) -> tuple[GroupRow, ...]:
    members: dict[str, list[str]] = {}
    for key, info in infos.items():
        for label in keys_of(info):
            members.setdefault(label, []).append(verdict_of[key])
    rows = []
    for label, verdicts in sorted(members.items()):
        counts = _count(verdicts)
        failing = sum(counts[v] for v in ("Failed", "Timeout", "Error", "Invalid"))
        rows.append(
            GroupRow(
                label=label,
                counts=counts,
                total=len(verdicts),
                passed=counts["Passed"],
                failing=failing,
            )
        )
    return tuple(rows)


def _scenario_view(
    info: records.ScenarioInfo,
    stored: records.StoredOutcome | None,
    earlier: Sequence[records.StoredOutcome],
    extra: details.ScenarioDetails,
    change: str,
) -> ScenarioView:
    outcome = stored.outcome if stored else None
    return ScenarioView(
        anchor=anchor(info.scenario_id),
        scenario=info,
        verdict=outcome.verdict.value if outcome else NOT_RUN,
        reason=outcome.reason if outcome else "the campaign stopped before this scenario ran",
        attempts=outcome.attempts if outcome else 0,
        metrics=tuple(
            (name, _metric(value))
            for name, value in sorted((outcome.metrics if outcome else {}).items())
        ),
        simulated_seconds=outcome.simulated_seconds if outcome else 0.0,
        wall_seconds=outcome.wall_seconds if outcome else 0.0,
        artifacts=tuple(sorted((outcome.artifacts if outcome else {}).items())),
        versions=tuple(
            (_version_label(name), value)
            for name, value in sorted((outcome.versions if outcome else {}).items())
        ),
        ignored_elements=outcome.ignored_elements if outcome else (),
        history=tuple((s.outcome.attempts, s.verdict.value, s.outcome.reason) for s in earlier),
        trajectory_svg=plots.trajectories(extra.trajectories),
        timeline_svgs=tuple(svg for svg in map(plots.timeline, extra.timelines) if svg),
        notes=extra.notes,
        change=change,
    )


def _metric(value: float) -> str:
    if math.isnan(value):
        return "n/a"
    if math.isinf(value):
        return "∞" if value > 0 else "-∞"
    return f"{value:.4g}"
