"""Preparing a local run: the request, manifest, output folder, frozen list, and the task recipe.

Everything here happens before a worker starts, and every problem is a ScenarioError with a
message that says what to do (exit code 2 in the CLI): an invalid manifest, an output folder that
belongs to another campaign, a frozen list that does not match the folder it should resume, or a
selection that found nothing.
"""

from __future__ import annotations

import dataclasses
import datetime
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from simtest_operator.api import converting, manifestfiles, v1alpha1
from simtest_operator.api.v1alpha1.search import SearchSpec
from simtest_operator.drivermodel import SutConfig
from simtest_operator.errors import ScenarioError, SourceError
from simtest_operator.openscenario import headers
from simtest_operator.runner import outputs, resolving, scheduling, suts, tasks
from simtest_operator.scenarios import selecting, uris
from simtest_operator.scenarios.batching import ExecutionPolicy
from simtest_operator.scenarios.locating import Locator
from simtest_operator.scenarios.pinned import FrozenList, PinnedScenario, sha256_hex
from simtest_operator.scenarios.querying import SecretProvider
from simtest_operator.scenarios.resolving import FetchContext
from simtest_operator.scenarios.specs import DatabaseSource, GraphqlSource, RestSource, Selection
from simtest_operator.settings import Settings
from simtest_operator.verdicts import ScenarioOutcome, Verdict


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LocalRunRequest:
    """Everything ``simtest run`` decided from its options."""

    manifest: Path | None
    """The TestCampaign manifest; None with ``rerun_failed`` uses that run's copy."""
    output: Path
    settings: Settings
    execute: tasks.ExecuteFn
    """Runs one task in a worker (the engine adapter, or the test double)."""
    parallel: int | None = None
    """Worker processes; None means all cores (capped by ``spec.execution.maxParallel``)."""
    frozen: Path | None = None
    """A frozen list to run instead of resolving the sources."""
    rerun_failed: Path | None = None
    """An earlier output folder whose non-passed scenarios to run again."""
    database: str | None = None
    """Results store (DSN or path); None: the campaign's secret, else SQLite in ``output``."""
    secrets: SecretProvider | None = None
    cpu_count: int = 1


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SearchPlan:
    """What a local search starts from."""

    spec: SearchSpec
    base: PinnedScenario
    """The logical scenario, pinned (id ``spec.scenario``): a scenario file or a
    ParameterValueDistribution."""
    path: Path
    """Its file on this machine (sha256 verified)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Plan:
    """A run, fully decided, before anything executes."""

    name: str
    manifest_sha256: str
    spec: v1alpha1.TestCampaignSpec
    output: outputs.OutputDir
    frozen: FrozenList
    by_id: Mapping[str, PinnedScenario]
    previous: Mapping[str, ScenarioOutcome]
    """Results already in the output folder (a resumed run)."""
    finished: frozenset[str]
    """Scenarios with a final verdict already: they are not run again."""
    resumed: bool
    started_at: datetime.datetime
    run_key: str | None
    policy: ExecutionPolicy
    fetch: FetchContext
    graphql_sources: tuple[DatabaseSource, ...]
    """The scenario databases (GraphQL and REST) asked again for inline items on a resume."""
    settings: Settings
    sut: SutConfig
    record: bool
    notes: tuple[str, ...]
    search: SearchPlan | None = None
    """``spec.search`` when this run searches (not when it reruns a given list): the frozen list
    then holds the proposals made so far and grows as the search proposes."""


def prepare(request: LocalRunRequest, *, now: datetime.datetime) -> Plan:
    """Read the manifest, settle the output folder and the frozen list."""
    manifest_path = request.manifest
    if manifest_path is None:
        if request.rerun_failed is None:
            raise ScenarioError("give a manifest (or --rerun-failed with an earlier output folder)")
        manifest_path = request.rerun_failed / outputs.MANIFEST
    text, manifest = read_manifest(manifest_path)
    spec = manifest.spec
    digest = sha256_hex(text.encode())
    out = outputs.OutputDir(request.output)
    fetch = FetchContext(
        base_dir=manifest_path.absolute().parent,
        cache_dir=request.settings.cache.sources,
        secrets=request.secrets,
    )
    selection = converting.selection(spec.scenarios)
    graphql = tuple(s for s in selection.sources if isinstance(s, GraphqlSource | RestSource))
    resumed = out.exists()
    notes: list[str] = []
    logical: PinnedScenario | None = None
    started_at, run_key = now, None
    if resumed:
        state = out.read_state()
        if state.manifest_sha256 != digest:
            raise ScenarioError(
                f"output folder {out.root} holds a run of a different manifest (or an edited "
                "one); choose another --output, or delete the folder to start over"
            )
        frozen = out.read_frozen()
        requested = _requested_list(request)
        if requested is not None and _pins(requested) != _pins(frozen):
            raise ScenarioError(
                f"output folder {out.root} holds a run of another scenario list; "
                "choose another --output"
            )
        started_at = _parse_time(state.started_at) or now
        run_key = state.run_key or None
    else:
        _check_empty(out.root)
        requested = _requested_list(request)
        seed = spec.environment.simulator.seed
        if requested is not None:
            frozen = requested
        elif spec.search is not None:
            searched = resolving.freeze_search(
                selection, fetch, campaign=manifest.name, scenario=spec.search.scenario, seed=seed
            )
            logical = searched.scenarios[0]
            frozen = dataclasses.replace(searched, scenarios=())
        else:
            frozen = resolving.freeze(selection, fetch, campaign=manifest.name, seed=seed)
        notes.extend(frozen.notes)
        if not frozen.scenarios and (spec.search is None or requested is not None):
            raise ScenarioError(
                "no scenarios selected: the sources hold no file matching the include/exclude "
                f"globs and selector{'; ' + '; '.join(frozen.notes) if frozen.notes else ''}"
            )
        out.write_text(out.manifest, text)
        out.write_frozen(frozen)
        out.write_state(
            outputs.RunState(
                campaign=manifest.name,
                manifest_sha256=digest,
                state="running",
                started_at=now.isoformat(),
            )
        )
    previous = out.read_results(frozen) if resumed else {}
    simulator = spec.environment.simulator
    search = None
    if spec.search is not None and request.frozen is None and request.rerun_failed is None:
        search = _search_plan(spec.search, logical, frozen, selection, fetch)
    return Plan(
        name=manifest.name,
        manifest_sha256=digest,
        spec=spec,
        output=out,
        frozen=frozen,
        by_id={s.id: s for s in frozen.scenarios},
        previous=previous,
        finished=outputs.finished_ids(previous),
        resumed=resumed,
        started_at=started_at,
        run_key=run_key,
        policy=converting.execution(spec.execution),
        fetch=fetch,
        graphql_sources=graphql,
        settings=dataclasses.replace(request.settings, simulation=converting.simulation(simulator)),
        sut=suts.reached_here(converting.sut(spec.environment.sut), request.settings),
        record=simulator.record and spec.artifacts.keep_recordings,
        notes=tuple(notes),
        search=search,
    )


def _search_plan(
    spec: SearchSpec,
    logical: PinnedScenario | None,
    frozen: FrozenList,
    selection: Selection,
    fetch: FetchContext,
) -> SearchPlan:
    """The logical scenario of a search: as just resolved, else (a resumed run) pinned like the
    proposals made so far."""
    base = logical
    if base is None:
        if not frozen.scenarios:
            raise ScenarioError(
                "this output folder holds a search that proposed nothing yet; delete it and "
                "start again"
            )
        made = frozen.scenarios[0]
        base = PinnedScenario(
            id=spec.scenario,
            source=made.source,
            sha256=made.sha256,
            overrides=dict(selection.overrides),
        )
    try:
        path = Locator(fetch).locate(base)
        if logical is None and not path.as_posix().endswith(f"/{spec.scenario}"):
            # The proposals run another file: the logical scenario is a distribution naming
            # it. Pinned again here; LocalSearch checks it still names the file they ran.
            base = resolving.freeze_search(
                selection, fetch, campaign=frozen.campaign, scenario=spec.scenario
            ).scenarios[0]
            path = Locator(fetch).locate(base)
    except SourceError as exc:
        raise ScenarioError(f"spec.search.scenario {spec.scenario!r}: {exc}") from exc
    return SearchPlan(spec=spec, base=base, path=path)


def read_manifest(path: Path) -> tuple[str, v1alpha1.Manifest[v1alpha1.TestCampaignSpec]]:
    """The manifest's text and the validated TestCampaign in it."""
    text, documents = manifestfiles.read(path)
    if len(documents) != 1:
        raise ScenarioError(
            f"expected exactly one TestCampaign document, found {len(documents)}", file=str(path)
        )
    return text, v1alpha1.parse_campaign(documents[0], source=str(path))


def task_factory(plan: Plan, paths: Mapping[str, Path]) -> scheduling.TaskFactory:
    """How to build the task of (scenario, attempt)."""

    def make(pinned: PinnedScenario, attempt: int) -> tasks.ScenarioTask:
        return tasks.ScenarioTask(
            scenario_id=pinned.id,
            scenario_path=paths[pinned.id],
            source_root=uris.source_root(paths[pinned.id], pinned.source),
            overrides=dict(pinned.overrides),
            out_dir=plan.output.scenario_dir(pinned.id),
            attempt=attempt,
            sut=plan.sut,
            criteria=converting.criteria(plan.spec.evaluation, pinned.id),
            settings=plan.settings,
            record=plan.record,
            timeout_seconds=plan.policy.timeout_seconds,
        )

    return make


def header_labels(path: Path | None) -> tuple[tuple[str, ...], str, str]:
    """(tags, category, road) of a scenario file for reports; blanks when unreadable."""
    if path is None:
        return (), "", ""
    try:
        header = headers.read_header(path)
    except ScenarioError:
        return (), "", ""
    props = header.properties
    road = selecting.label_value(props, "road") or Path(header.road_file).name
    return (
        tuple(sorted(selecting.tags_of(props))),
        selecting.label_value(props, "category") or "",
        road,
    )


def _requested_list(request: LocalRunRequest) -> FrozenList | None:
    if request.frozen is not None:
        frozen_file = outputs.OutputDir(request.frozen.parent)
        return FrozenList.from_json(
            frozen_file.read_json(request.frozen), where=str(request.frozen)
        )
    if request.rerun_failed is not None:
        earlier = outputs.OutputDir(request.rerun_failed)
        if not earlier.frozen.is_file():
            raise ScenarioError(f"{request.rerun_failed} is not the output folder of a run")
        frozen = earlier.read_frozen()
        results = earlier.read_results(frozen)
        again = [
            s.id
            for s in frozen.scenarios
            if s.id not in results or results[s.id].verdict is not Verdict.PASSED
        ]
        if not again:
            raise ScenarioError(
                f"nothing to rerun: every scenario in {request.rerun_failed} passed"
            )
        return frozen.subset(again)
    return None


def _pins(frozen: FrozenList) -> list[tuple[str, str, dict[str, str]]]:
    return [(s.id, s.sha256, dict(s.overrides)) for s in frozen.scenarios]


def _check_empty(root: Path) -> None:
    if root.exists() and (not root.is_dir() or any(root.iterdir())):
        raise ScenarioError(
            f"output folder {root} exists and holds no simtest run; choose an empty or new folder"
        )


def _parse_time(text: str) -> datetime.datetime | None:
    try:
        return datetime.datetime.fromisoformat(text)
    except ValueError:
        return None


def describe_plan(plan: Plan) -> Mapping[str, Any]:
    """Execution settings worth storing with the campaign record."""
    simulator = plan.spec.environment.simulator
    return {
        "batchSize": plan.policy.batch_size,
        "policy": plan.policy.policy.value,
        "timeoutSeconds": plan.policy.timeout_seconds,
        "retries": plan.policy.retries,
        "stepLength": simulator.step_length,
        "seed": simulator.seed,
        "record": plan.record,
        "scenarios": len(plan.frozen.scenarios),
    }
