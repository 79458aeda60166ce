"""Resolving a campaign: sources, globs, headers, selector, distributions -> frozen list.

This composes the domain layer (``scenarios``: fetching, globbing, pinning) with the OpenSCENARIO
layer (header reading, distribution expansion), which ``scenarios`` may not import. The operator
and ``simtest run`` both freeze through :func:`freeze`, so a campaign selects the same scenarios
on a laptop and in a cluster.

Rules (documented in docs/local-run.md):

* catalog files are never scenarios and are left out (counted in the notes);
* a file whose header cannot be read stays in the list: running it gives ``Invalid`` with the
  reason, which is more useful than a silently missing test;
* a ParameterValueDistribution expands into one run per parameter assignment, with id
  ``<distribution path>#<k>-<hash>`` and the distribution's values over the campaign overrides;
* ids are paths inside their source; a clash across sources gets the suffix ``~<source number>``;
* a search (``spec.search``) pins only its logical scenario (:func:`freeze_search`); its concrete
  scenarios enter the list as they are proposed (:func:`pin_proposal`), each with what replays
  the search (:func:`replay_search`).
"""

from __future__ import annotations

import collections
import dataclasses
import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from simtest_operator import openscenario
from simtest_operator.api.v1alpha1.search import SearchSpec
from simtest_operator.errors import ScenarioError, SourceError
from simtest_operator.openscenario import headers
from simtest_operator.scenarios import resolving, selecting, uris
from simtest_operator.scenarios.pinned import FrozenList, PinnedScenario, ProposalPin, sha256_hex
from simtest_operator.scenarios.specs import Selection
from simtest_operator.verdicts import Verdict

if TYPE_CHECKING:  # the engine (scikit-learn, optuna) loads only where a search runs
    from simtest_operator.search import Outcome, Proposal, Searcher, SearchSpace, SearchSummary

Expander = Callable[[Path, int], Sequence[openscenario.ConcreteRun]]
"""Expands a distribution file (with a seed for stochastic ones) into concrete runs."""


def _expand(path: Path, seed: int) -> Sequence[openscenario.ConcreteRun]:
    return openscenario.expand_distribution(path, seed=seed)


@dataclasses.dataclass(slots=True)
class _Collector:
    overrides: dict[str, str]
    entries: list[PinnedScenario] = dataclasses.field(default_factory=list)
    ids: set[str] = dataclasses.field(default_factory=set)
    skipped: collections.Counter[str] = dataclasses.field(default_factory=collections.Counter)
    notes: list[str] = dataclasses.field(default_factory=list)

    def add(
        self,
        ident: str,
        source_number: int,
        *,
        uri: str,
        path: Path,
        overrides: dict[str, str] | None = None,
    ) -> None:
        if ident in self.ids:
            ident = f"{ident}~{source_number}"
        self.ids.add(ident)
        self.entries.append(
            PinnedScenario(
                id=ident,
                source=uri,
                sha256=sha256_hex(path.read_bytes()),
                overrides={**self.overrides, **(overrides or {})},
            )
        )


def freeze(
    selection: Selection,
    ctx: resolving.FetchContext,
    *,
    campaign: str,
    seed: int = 42,
    expand: Expander = _expand,
) -> FrozenList:
    """Resolve every source of ``selection`` and return the campaign's frozen list."""
    collector = _Collector(overrides=dict(selection.overrides))
    infos = []
    for number, spec in enumerate(selection.sources, start=1):
        resolved = resolving.resolve(spec, ctx)
        infos.append(resolved.info)
        kept = selecting.by_globs(
            resolved.files, include=selection.include, exclude=selection.exclude
        )
        for rel in kept:
            _one(resolved, rel, number, selection, collector, seed=seed, expand=expand)
    notes = list(collector.notes)
    for reason, count in sorted(collector.skipped.items()):
        notes.append(f"left out {count} file(s): {reason}")
    return FrozenList(
        campaign=campaign,
        scenarios=tuple(collector.entries),
        sources=tuple(infos),
        notes=tuple(notes),
    )


def _one(
    resolved: resolving.ResolvedSource,
    rel: str,
    number: int,
    selection: Selection,
    collector: _Collector,
    *,
    seed: int,
    expand: Expander,
) -> None:
    path = resolved.root / rel
    uri = resolved.uris[rel]
    try:
        header: headers.FileHeader | None = headers.read_header(path)
    except ScenarioError as exc:
        header = None
        collector.notes.append(f"{rel}: header unreadable, kept (it will end as Invalid): {exc}")
    if header is not None:
        if header.kind is headers.FileKind.CATALOG:
            collector.skipped["catalog files"] += 1
            return
        if not selection.selector.empty and not selecting.matches(
            selection.selector, header.properties
        ):
            collector.skipped["not matching the selector"] += 1
            return
        if header.kind is headers.FileKind.DISTRIBUTION:
            _distribution(resolved, rel, number, collector, seed=seed, expand=expand)
            return
    collector.add(rel, number, uri=uri, path=path)


def _distribution(
    resolved: resolving.ResolvedSource,
    rel: str,
    number: int,
    collector: _Collector,
    *,
    seed: int,
    expand: Expander,
) -> None:
    path = resolved.root / rel
    try:
        runs = expand(path, seed)
    except ScenarioError as exc:
        # Keep the distribution itself: running it reports Invalid with this reason.
        collector.notes.append(f"{rel}: distribution cannot be expanded, kept as Invalid: {exc}")
        collector.add(rel, number, uri=resolved.uris[rel], path=path)
        return
    for run in runs:
        suffix = run.id.split("#", 1)[1] if "#" in run.id else run.id
        collector.add(
            f"{rel}#{suffix}",
            number,
            uri=resolved.uri_for(run.scenario),
            path=run.scenario,
            overrides=dict(run.overrides),
        )


# --- searches (spec.search) ---------------------------------------------------------------------

SEARCH_SUFFIX = "#search-"
"""A search's concrete scenario has the id ``<logical scenario>#search-<index>``."""


LOGICAL_SUFFIX = "#logical"
"""While a search freezes, a ParameterValueDistribution is pinned as itself under this suffix."""


def freeze_search(
    selection: Selection,
    ctx: resolving.FetchContext,
    *,
    campaign: str,
    scenario: str,
    seed: int = 42,
) -> FrozenList:
    """The logical scenario a search varies, pinned: a one-entry list (id ``scenario``).

    The selection is resolved as for any campaign, so the file is pinned from the same sources
    on a laptop and in a cluster; ``scenario`` must be one of the files it selects. A
    ParameterValueDistribution is pinned as itself, not expanded: the search spans its ranges,
    and its proposals run the scenario file it names (:func:`search_target`)."""
    frozen = freeze(selection, ctx, campaign=campaign, seed=seed, expand=_unexpanded)
    wanted = (scenario, f"{scenario}{LOGICAL_SUFFIX}")
    base = next((s for s in frozen.scenarios if s.id in wanted), None)
    if base is None:
        listed = ", ".join(s.id.removesuffix(LOGICAL_SUFFIX) for s in frozen.scenarios[:5])
        raise ScenarioError(
            f"spec.search.scenario {scenario!r} is not among the {len(frozen.scenarios)} "
            f"scenario(s) the selection resolves to (first: {listed or 'none'}); name a file of "
            "spec.scenarios as a path inside its source"
        )
    return dataclasses.replace(frozen, scenarios=(dataclasses.replace(base, id=scenario),))


def _unexpanded(path: Path, seed: int) -> Sequence[openscenario.ConcreteRun]:
    ident = f"{path.name}{LOGICAL_SUFFIX}"
    return [openscenario.ConcreteRun(id=ident, scenario=path, overrides={})]


def search_target(base: PinnedScenario, path: Path, space: SearchSpace) -> PinnedScenario:
    """The pin a search's proposals run: the logical scenario ``base`` itself, or, when it is a
    ParameterValueDistribution (``path``: its local copy), the scenario file the distribution
    names, pinned from the same source (same id: proposals stay ``<distribution>#search-<i>``).
    ScenarioError when that file cannot be pinned (outside the source)."""
    target = space.scenario
    if target is None or target.resolve() == path.resolve():
        return base
    try:
        uri = uris.sibling(base.source, path, target)
    except SourceError as exc:
        raise ScenarioError(f"spec.search.scenario {base.id!r}: {exc}") from exc
    return dataclasses.replace(base, source=uri, sha256=sha256_hex(target.read_bytes()))


def pin_proposal(
    base: PinnedScenario, proposal: Proposal, *, told: Sequence[int]
) -> PinnedScenario:
    """The frozen-list entry of a proposal: the logical scenario with the proposal's parameter
    values over the campaign's overrides, and what replays it (index, basis, the tells before)."""
    return PinnedScenario(
        id=f"{base.id}{SEARCH_SUFFIX}{proposal.index}",
        source=base.source,
        sha256=base.sha256,
        overrides={**base.overrides, **proposal.overrides()},
        proposal=ProposalPin(
            index=proposal.index,
            basis=proposal.basis,
            told=tuple(told),
            values={name: json.dumps(value) for name, value in proposal.values.items()},
        ),
    )


def proposal_of(pin: ProposalPin) -> Proposal:
    """The engine's proposal a frozen-list entry pins (values back from their JSON text)."""
    from simtest_operator.search import Proposal

    values: dict[str, float | str] = {}
    for name, text in pin.values.items():
        value = json.loads(text)
        values[name] = value if isinstance(value, str) else float(value)
    return Proposal(index=pin.index, values=values, basis=pin.basis)


def replay_inputs(
    pins: Sequence[ProposalPin], outcomes: Mapping[int, Outcome]
) -> tuple[list[Proposal], list[tuple[int, Outcome]]]:
    """(proposals, tells in the order told) for :meth:`Searcher.replay`, from the pinned
    proposals in index order and the outcomes by proposal index; ScenarioError when a tell's
    outcome is missing or the pins are not one unbroken sequence."""
    proposals: list[Proposal] = []
    tells: list[tuple[int, Outcome]] = []
    for expected, pin in enumerate(sorted(pins, key=lambda p: p.index)):
        if pin.index != expected:
            raise ScenarioError(f"search proposal {expected} is missing from the frozen list")
        for index in pin.told:
            outcome = outcomes.get(index)
            if outcome is None:
                raise ScenarioError(
                    f"search proposal {pin.index} was asked after the result of proposal "
                    f"{index}, which is no longer recorded; the search cannot be replayed"
                )
            tells.append((index, outcome))
        if len(tells) != pin.basis:
            raise ScenarioError(
                f"search proposal {pin.index} says {pin.basis} results were told before it, "
                f"the frozen list records {len(tells)}"
            )
        proposals.append(proposal_of(pin))
    return proposals, tells


@dataclasses.dataclass(frozen=True, slots=True)
class ReplayedSearch:
    """A searcher rebuilt from a frozen list, and what it was told on the way."""

    searcher: Searcher
    pinned: Sequence[tuple[int, Outcome]]
    """Tells the pinned proposals record, in the order told."""
    unpinned: Sequence[int]
    """Tells made after the last proposal was asked, in index order: the next proposal's
    ``told``."""


def replay_search(
    spec: SearchSpec,
    space: SearchSpace,
    pins: Sequence[ProposalPin],
    outcomes: Mapping[int, Outcome],
) -> ReplayedSearch:
    """The searcher as a frozen list left it (a resumed run, a restarted operator): each pinned
    proposal asked again after the tells recorded before it, then told every other outcome.

    CPU-bound (every proposal is asked again: a classifier fit each for ``boundary``); the
    operator calls it off its event loop. ScenarioError or ReplayError when the record does
    not replay."""
    from simtest_operator.search import Searcher

    proposals, tells = replay_inputs(pins, outcomes)
    searcher = Searcher.replay(spec, space, proposals, tells)
    told = {index for index, _ in tells}
    unpinned = sorted(set(outcomes) - told)
    for index in unpinned:
        searcher.tell(index, outcomes[index])
    return ReplayedSearch(searcher=searcher, pinned=tells, unpinned=unpinned)


def search_outcome(verdict: Verdict, metrics: Mapping[str, float]) -> Outcome:
    """What the searcher learns from a final result."""
    from simtest_operator.search import Outcome

    return Outcome(verdict=verdict, metrics=dict(metrics))


def search_record(
    spec: SearchSpec,
    space: SearchSpace,
    entries: Sequence[PinnedScenario],
    summary: SearchSummary,
) -> dict[str, Any]:
    """What the results store keeps with a searching campaign (``settings.search``), written by
    ``simtest run`` and the operator alike: enough to summarise, plot and export the search
    again without the scenario file."""
    return {
        "spec": spec.to_wire(),
        "dimensions": [dataclasses.asdict(d) for d in space.dimensions],
        "proposals": [
            {"id": p.id, **p.proposal.to_json()} for p in entries if p.proposal is not None
        ],
        "summary": summary.model_dump(mode="json"),
    }
