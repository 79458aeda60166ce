"""A finished search as the results store keeps it: its record, its report section, its export.

A search's record travels with its campaign in the store (``settings.search``: the spec, the
dimensions, every proposal with its values, the summary), written by ``simtest run`` and by the
operator alike. This module turns a stored run back into the engine's terms -- proposals and
outcomes over the same space -- for the report's and the results UI's *Search* section and for
``simtest search export``. The engine sits above the results layer, so the section is built
here and handed to the report as text and pictures.
"""

from __future__ import annotations

import base64
import dataclasses
from collections.abc import Mapping, Sequence
from pathlib import Path

from simtest_operator.api.v1alpha1.search import SearchSpec
from simtest_operator.errors import ResultsError, SourceError
from simtest_operator.results import comparing, opening, records, reportmodel, stores
from simtest_operator.runner import resolving
from simtest_operator.scenarios import uris
from simtest_operator.scenarios.locating import Locator
from simtest_operator.scenarios.pinned import PinnedScenario, ProposalPin
from simtest_operator.scenarios.resolving import FetchContext
from simtest_operator.search import (
    Dimension,
    Outcome,
    Proposal,
    SearchSpace,
    SearchSummary,
    plot_pairs,
    summarise,
)
from simtest_operator.search import export_scenarios as write_scenarios
from simtest_operator.verdicts import Verdict

Records = Sequence[tuple[Proposal, Outcome]]
SHOWN_REGIONS = 5
"""Failure regions described one by one; the rest are counted (``search.json`` has them all)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Recorded:
    """A search with its results, in the engine's terms."""

    spec: SearchSpec
    space: SearchSpace
    scenario: str
    """The logical scenario's id; proposal ``i`` is ``<scenario>#search-<i>``."""
    records: Records
    """(proposal, final outcome) in index order."""
    summary: SearchSummary


def outcomes_of(
    entries: Sequence[PinnedScenario], final: Mapping[str, tuple[str, Mapping[str, float]]]
) -> list[tuple[Proposal, Outcome]]:
    """(proposal, outcome) of every entry with a final verdict (``final``: id -> (verdict,
    metrics); Skipped ones left out: they did not run)."""
    out = []
    for pinned in entries:
        found = final.get(pinned.id)
        if pinned.proposal is None or found is None or found[0] == "Skipped":
            continue
        told = resolving.search_outcome(Verdict(found[0]), found[1])
        out.append((resolving.proposal_of(pinned.proposal), told))
    return out


def recorded(
    campaign: records.CampaignRecord, stored: Sequence[records.StoredOutcome]
) -> Recorded | None:
    """The search of a stored run (None for a run that did not search, or one recorded before
    it ended)."""
    raw = campaign.info.settings.get("search")
    if not isinstance(raw, Mapping) or "dimensions" not in raw:
        return None
    try:
        spec = SearchSpec.model_validate(raw["spec"])
        space = SearchSpace(
            scenario=None,
            dimensions=tuple(
                Dimension(**{**d, "choices": tuple(d["choices"]) if d.get("choices") else None})
                for d in raw["dimensions"]
            ),
        )
        entries = [
            PinnedScenario(
                id=str(p["id"]),
                source="-",
                sha256="0" * 64,
                proposal=ProposalPin.from_json(p, where="the stored search"),
            )
            for p in raw["proposals"]
        ]
    except (KeyError, TypeError, ValueError, SourceError) as exc:
        raise ResultsError(
            f"run {campaign.run_key}: its search record is unreadable: {exc}"
        ) from exc
    final = {
        key: (s.verdict.value, dict(s.outcome.metrics))
        for key, s in comparing.final_outcomes(stored).items()
    }
    runs = outcomes_of(entries, final)
    return Recorded(
        spec=spec,
        space=space,
        scenario=spec.scenario,
        records=runs,
        summary=summarise(space, runs, spec.objectives),
    )


def section(search: Recorded) -> reportmodel.SearchSection:
    """The report's and the UI's *Search* section: facts, the most critical runs, the plots."""
    summary, spec = search.summary, search.spec
    facts = [
        ("Logical scenario", spec.scenario),
        ("Strategy", f"{spec.strategy.value}, seed {spec.seed}"),
        ("Runs", f"{summary.runs} of a budget of {spec.budget}"),
        ("Failures (Failed or Timeout)", str(summary.failures)),
        ("Failure regions", str(len(summary.regions))),
    ]
    for number, region in enumerate(summary.regions[:SHOWN_REGIONS], start=1):
        bounds = ", ".join(
            f"{name} {_text(lo)}..{_text(hi)}" for name, (lo, hi) in region.bounds.items()
        )
        facts.append((f"Region {number} ({region.count} failures)", bounds))
    if len(summary.regions) > SHOWN_REGIONS:
        facts.append(("Further regions", str(len(summary.regions) - SHOWN_REGIONS)))
    if summary.boundary is not None:
        facts.append(
            (
                "Estimated boundary",
                f"{summary.boundary.failure_share:.0%} of the space predicted to fail "
                f"(classifier on {summary.boundary.training_points} runs, "
                f"{summary.boundary.training_misclassification:.0%} of them misclassified)",
            )
        )
    if summary.not_judged:
        facts.append(
            ("Runs without a verdict on the system (Error, Invalid)", str(summary.not_judged))
        )
    objective = spec.objectives[0]
    if summary.best is not None:
        facts.append((f"Most critical ({objective.metric})", f"{summary.best:.4g}"))
    critical = tuple(
        (
            f"{search.scenario}{resolving.SEARCH_SUFFIX}{run.index}",
            ", ".join(f"{name}={_text(value)}" for name, value in run.values.items()),
            run.verdict,
        )
        for run in summary.critical
    )
    plots = tuple(
        (f"{x} / {y}" if x != y else x, "data:image/png;base64," + base64.b64encode(png).decode())
        for x, y, png in plot_pairs(search.space, search.records, summary)
    )
    return reportmodel.SearchSection(facts=tuple(facts), critical=critical, plots=plots)


def section_of(
    campaign: records.CampaignRecord, stored: Sequence[records.StoredOutcome]
) -> reportmodel.SearchSection | None:
    """The *Search* section of a stored run, None when it did not search (the results UI and
    ``simtest report`` are handed this)."""
    search = recorded(campaign, stored)
    return None if search is None else section(search)


def lines(search: Recorded) -> list[str]:
    """The summary as a few lines for the terminal."""
    built = section(search)
    out = [f"{label}: {value}" for label, value in built.facts]
    out.extend(
        f"critical: {ident} ({values}) {verdict}" for ident, values, verdict in built.critical[:5]
    )
    return out


def export(
    target: str | Path,
    out_dir: Path,
    *,
    fetch: FetchContext,
    top: int = 10,
    run_key: str | None = None,
) -> list[Path]:
    """Write the ``top`` most critical concrete scenarios of a stored search as ``.xosc`` files
    (the logical scenario fetched as pinned, its parameter values replaced), with copies of the
    road network and catalogs they reference: the folder runs on its own."""
    with opening.open_store(target, create=False) as store:
        campaign = _campaign(store, run_key)
        stored = store.outcomes(campaign.run_key, final_only=False)
        listed = {s.scenario_id: s for s in store.scenarios(campaign.run_key)}
    search = recorded(campaign, stored)
    if search is None:
        raise ResultsError(f"run {campaign.run_key} did not search (no spec.search record)")
    chosen = search.summary.critical[:top]
    if not chosen:
        return []
    by_index = {p.index: p for p, _ in search.records}
    first = listed.get(f"{search.scenario}{resolving.SEARCH_SUFFIX}{chosen[0].index}")
    if first is None:
        raise ResultsError(f"run {campaign.run_key} does not list its search's scenarios")
    logical = PinnedScenario(id=search.scenario, source=first.source, sha256=first.sha256)
    try:
        path = Locator(fetch).locate(logical)
    except SourceError as exc:
        raise ResultsError(f"cannot fetch the logical scenario {search.scenario}: {exc}") from exc
    root = uris.source_root(path, logical.source)
    return write_scenarios(path, [by_index[run.index] for run in chosen], out_dir, source_root=root)


def _campaign(store: stores.ResultSource, run_key: str | None) -> records.CampaignRecord:
    if run_key is None:
        newest = store.campaigns(limit=1)
        if not newest:
            raise ResultsError("the results store holds no campaign run yet")
        return newest[0]
    found = store.campaign(records.RunKey(run_key))
    if found is None:
        raise ResultsError(f"no campaign run {run_key!r} in the results store")
    return found


def _text(value: object) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)
