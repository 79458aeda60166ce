"""Executing one scenario: simulation + online evaluation + recording -> one outcome.

``sim``, ``evaluation`` and ``recording`` sit on the same layer and do not know each other; this
module wires them: the simulation yields a snapshot per step, the evaluator judges each one, the
recorder writes them (thinned to the recording rate). Every way a run can end becomes a verdict
with a one-line reason -- bad or unsupported input ``Invalid``, infrastructure ``Error``, a
violated criterion ``Failed``, the time limit ``Timeout`` -- never an exception.

libsumo allows one simulation per process: call :func:`run_scenario` from one thread per process
(the local executor and ``simtest scenario check`` use worker processes).
"""

from __future__ import annotations

import dataclasses
import json
import multiprocessing
import tempfile
import time
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path

from simtest_operator import evaluation, opendrive, provenance, recording
from simtest_operator.errors import ScenarioError, SimtestError
from simtest_operator.evaluation import quality
from simtest_operator.openscenario import Deviation, LoadOptions, model, rulesets
from simtest_operator.recording import objects
from simtest_operator.runner import suts
from simtest_operator.runner.tasks import SUT_LOG
from simtest_operator.settings import SimulationSettings
from simtest_operator.sim import BackendChoice, Simulation, SutConfig, open_simulation
from simtest_operator.snapshots import WorldSnapshot
from simtest_operator.sut import launching
from simtest_operator.verdicts import ScenarioOutcome, Verdict

Sample = tuple[float, float, float, float, float]
"""(t, x, y, heading, speed) of an entity's reference point, as in esmini-reference.json."""


def soft_limit(timeout: float) -> float:
    """The engine's own wall-clock limit for a scenario timeout of ``timeout`` seconds.

    A little below the timeout, so a slow run normally ends as a clean ``Timeout`` with its
    metrics and a closed recording before the worker's kill (local) or the pod's deadline lands.
    Local workers and pods both use it: one limit, so equal verdicts hold by construction.
    """
    return max(timeout * 0.9, timeout - 2.0)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RunRequest:
    """Everything needed to run one scenario once."""

    scenario: Path
    nets_dir: Path
    """Cache directory of converted SUMO networks (``settings.cache.nets``)."""
    scenario_id: str | None = None
    """Id for results and the recording; default: the file name."""
    overrides: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """Global parameter overrides (ParameterValueDistribution runs, campaign parameters)."""
    sut: SutConfig = dataclasses.field(default_factory=SutConfig)
    criteria: evaluation.Criteria = dataclasses.field(default_factory=evaluation.Criteria)
    simulation: SimulationSettings = dataclasses.field(default_factory=SimulationSettings)
    output_dir: Path | None = None
    """Where the recording, log and result file go; None writes nothing."""
    record: bool = True
    """Keep the recording in ``output_dir``. Without it the run still records (to a temporary
    file it deletes) and holds a pass to the same evidence checks: every command judges a file
    alike."""
    wall_clock_limit: float | None = None
    """Seconds of wall time after which the run stops as ``Timeout``."""
    backend: BackendChoice = BackendChoice.SUMO
    loading: LoadOptions = dataclasses.field(default_factory=LoadOptions)
    """Strict mode, source root and map libraries for reading the scenario."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RunReport:
    """The outcome plus the details reports and reference comparisons need."""

    outcome: ScenarioOutcome
    storyboard_complete: bool
    collisions: tuple[evaluation.Collision, ...] = ()
    samples: Mapping[str, tuple[Sample, ...]] = dataclasses.field(default_factory=dict)
    """1 Hz samples per entity (t, x, y, heading, speed)."""
    ego: str | None = None
    intended: tuple[str, ...] = ()
    """Deliberate differences from a reference player (SUT-driven ego, controllers)."""
    net_from_cache: bool = False
    startup_seconds: float = 0.0
    """Wall time to load the scenario, map and network and start the backend."""
    deviations: tuple[Deviation, ...] = ()
    """Accepted deviations from the OpenSCENARIO schema (empty under strict mode)."""
    rules: str = ""
    """The rule set the scenario ran under and why (``ScenarioRunner (criteria_* conditions)``);
    empty when it did not load."""


class _Samples:
    """1 Hz samples in the map's reported frame: the file frame moved by the OpenDRIVE header
    offset, if any (esmini reports positions so; the simulation itself runs in the file frame)."""

    __slots__ = ("_frame", "_next", "data")

    def __init__(self, frame: opendrive.HeaderOffset | None = None) -> None:
        self.data: dict[str, list[Sample]] = {}
        self._next = 0.0
        self._frame = frame

    def observe(self, snapshot: WorldSnapshot) -> None:
        if snapshot.time + 1e-6 < self._next:
            return
        self._next = float(int(snapshot.time + 1e-6) + 1)
        for e in snapshot.entities:
            x, y, heading = e.x, e.y, e.heading
            if self._frame is not None:
                x, y, heading = self._frame.apply(x, y, heading)
            sample = (
                round(snapshot.time, 3),
                round(x, 3),
                round(y, 3),
                round(heading, 4),
                round(e.speed, 3),
            )
            self.data.setdefault(e.name, []).append(sample)


def run_scenario(
    request: RunRequest, *, processes: launching.SutProcesses | None = None
) -> RunReport:
    """Run one scenario to its verdict; never raises for scenario or simulator problems.

    ``processes``: the calling worker's warm SUT processes (``lifetime: worker``); without it
    every run starts its SUT afresh.
    """
    started = time.perf_counter()
    scenario_id = request.scenario_id or request.scenario.name
    out = request.output_dir
    log: list[str] = [f"scenario {request.scenario} id {scenario_id}"]
    artifacts: dict[str, str] = {}
    versions = {**provenance.versions(), "sut": f"{request.sut.name} {request.sut.version}"}
    try:
        opened = open_simulation(
            request.scenario,
            sut=request.sut,
            settings=request.simulation,
            nets_dir=request.nets_dir,
            overrides=request.overrides,
            backend=request.backend,
            loading=request.loading,
        )
    except SimtestError as exc:
        verdict = Verdict.INVALID if isinstance(exc, ScenarioError) else Verdict.ERROR
        wall = time.perf_counter() - started
        outcome = ScenarioOutcome(
            scenario_id=scenario_id,
            verdict=verdict,
            reason=_one_line(exc),
            wall_seconds=wall,
            versions=versions,
        )
        return RunReport(outcome=outcome, storyboard_complete=False)
    simulation = opened.simulation
    deviations = opened.scenario.deviations
    log.extend(f"accepted deviation: {d.describe()}" for d in deviations)
    log.append(
        f"network {opened.net_file} (cache {'hit' if opened.net_from_cache else 'miss'}, "
        f"{opened.net_seconds:.2f} s); ego {simulation.ego}"
    )
    log.append(f"rules: {simulation.rules.describe()}")
    checks = evaluation.ScenarioCriteria.of(opened.scenario, roads=simulation.world.roads)
    evaluator = evaluation.OnlineEvaluator(
        request.criteria,
        ego=simulation.ego,
        off_road=simulation.off_road,
        coupled=simulation.coupled,
        scenario_criteria=checks,
    )
    roads = simulation.world.roads
    samples = _Samples(roads.document.offset if roads is not None else None)
    recorder = None
    invalid: str | None = None
    error: str | None = None
    wall_hit = False
    startup = 0.0
    link = suts.SutLink(request.sut, processes)
    logic = opened.scenario.road_network.logic_file
    # A run that keeps no recording still records, to a scratch file, so that a pass meets the
    # same evidence checks (``scenario check`` judges a file as ``scenario run`` does).
    keep = out is not None and request.record
    scratch = None if keep else tempfile.TemporaryDirectory(prefix="simtest-evidence-")
    recording_path = Path(scratch.name if scratch is not None else str(out)) / "recording.mcap"
    try:
        refusal = _scenario_runner_refusal(simulation, opened.scenario, checks)
        if refusal is not None:
            raise ScenarioError(refusal)
        link.attach(
            simulation,
            scenario_id=scenario_id,
            settings=request.simulation,
            map_reference=logic.name if logic is not None else "map",
            versions=versions,
            log=out / SUT_LOG if out is not None else None,
        )
        recorder = recording.Recorder(
            recording_path,
            info=recording.RecordingInfo(
                scenario_id=scenario_id, seed=request.simulation.seed, versions=versions
            ),
            opendrive=logic.read_bytes() if logic is not None else None,
            map_reference=logic.name if logic is not None else "map",
            host_id=_ego_id(simulation),
            period=1.0 / request.simulation.record_hz,
            signals=simulation.world.signal_index.controls,
        )
        if keep:
            artifacts["recording"] = str(recording_path)
        snapshot = simulation.start()
        startup = time.perf_counter() - started
        wall_hit = _loop(request, simulation, snapshot, evaluator, samples, recorder, started)
    except ScenarioError as exc:
        invalid = _one_line(exc)
    except SimtestError as exc:
        error = _one_line(exc)
    except Exception as exc:
        error = f"internal error: {type(exc).__name__}: {exc}"
    finally:
        link.close()
        simulation.close()
        if out is not None and (out / SUT_LOG).is_file():
            artifacts["sutLog"] = str(out / SUT_LOG)
        for at, env in simulation.environments:
            log.append(f"environment {env.name} at t={at:g} s (recorded, not rendered)")
            if recorder is not None:
                recorder.add_environment(at, env.name, env.settings)
        if recorder is not None:
            for jump in simulation.discontinuities:
                recorder.add_discontinuity(jump)
            recorder.close()
    wall = time.perf_counter() - started
    facts = evaluation.RunFacts(
        simulated_seconds=simulation.time,
        wall_seconds=wall,
        storyboard_complete=simulation.complete,
        invalid_reason=invalid,
        error_reason=error,
        wall_limit_hit=wall_hit,
        ignored_elements=simulation.ignored,
        monitors=simulation.monitors,
    )
    judgement = evaluation.judge(evaluator, facts)
    verdict, reason = judgement.verdict, judgement.reason
    if verdict is Verdict.PASSED and recorder is not None:
        evidence = _evidence(
            recorder.path,
            simulated_seconds=simulation.time,
            map_expected=logic is not None,
            host_expected=simulation.ego is not None,
        )
        log.append(f"evidence: {'complete' if evidence.complete else evidence.incomplete_reason()}")
        if not evidence.complete:
            verdict, reason = Verdict.ERROR, evidence.incomplete_reason()
    if scratch is not None:
        scratch.cleanup()
    extra = link.metrics(
        simulated=simulation.time,
        loop_seconds=wall - startup,
        pace=request.simulation.real_time_factor,
    )
    log.extend(note for note in (suts.behind_note(extra),) if note)
    outcome = ScenarioOutcome(
        scenario_id=scenario_id,
        verdict=verdict,
        reason=reason,
        metrics={**judgement.metrics, **extra},
        simulated_seconds=simulation.time,
        wall_seconds=wall,
        artifacts=artifacts,
        ignored_elements=simulation.ignored,
        versions=versions,
    )
    report = RunReport(
        outcome=outcome,
        storyboard_complete=simulation.complete,
        collisions=evaluator.collisions,
        samples={name: tuple(values) for name, values in samples.data.items()},
        ego=simulation.ego,
        intended=simulation.intended_differences,
        net_from_cache=opened.net_from_cache,
        startup_seconds=startup,
        deviations=deviations,
        rules=simulation.rules.describe(),
    )
    if out is not None:
        _write_outputs(out, report, log)
    return report


def _scenario_runner_refusal(
    simulation: Simulation,
    scenario: model.Scenario,
    checks: evaluation.ScenarioCriteria | None,
) -> str | None:
    """Why ScenarioRunner would refuse the file (it builds the stories' conditions, then the
    criteria, and raises on what it cannot build), or None; only under its rules."""
    if not simulation.rules.scenario_runner:
        return None
    refusal = rulesets.scenario_runner_refusal(scenario)
    if refusal is None and checks is not None:
        refusal = checks.refusal
    return refusal


def _loop(
    request: RunRequest,
    simulation: Simulation,
    snapshot: WorldSnapshot,
    evaluator: evaluation.OnlineEvaluator,
    samples: _Samples,
    recorder: recording.Recorder | None,
    started: float,
) -> bool:
    """Step until the storyboard completes, a limit is hit or a ScenarioRunner criterion ends the
    run (:attr:`~.evaluation.ScenarioCriteria.ends_run`); True when the wall limit hit."""
    limit = request.criteria.time_limit
    wall_limit = request.wall_clock_limit
    pace = request.simulation.real_time_factor
    paced_from = time.perf_counter() - simulation.time / pace if pace > 0 else 0.0
    steps = 0
    while True:
        evaluator.observe(snapshot)
        samples.observe(snapshot)
        if recorder is not None:
            recorder.write(snapshot)
        if simulation.complete or simulation.time >= limit - 1e-9:
            return False
        checks = evaluator.scenario_criteria
        if checks is not None and checks.ends_run:
            return False  # ScenarioRunner's failed EndofRoadTest ends its scenario tree
        steps += 1
        if pace > 0:  # no step before its wall time: simulated t at paced_from + t / pace
            ahead = paced_from + simulation.time / pace - time.perf_counter()
            if ahead > 0:
                time.sleep(ahead)
        wall_check = wall_limit is not None and (pace > 0 or steps % 200 == 0)
        if wall_check and time.perf_counter() - started > (wall_limit or 0.0):
            return True
        snapshot = simulation.step()


def _evidence(
    path: Path, *, simulated_seconds: float, map_expected: bool, host_expected: bool
) -> quality.Quality:
    """The recording's evidence quality, as ``simtest evaluate`` judges it: a recording that is
    incomplete or inconsistent cannot make a run ``Passed``."""
    try:
        decoded = objects.read_objects(path)
    except SimtestError as exc:
        return quality.Quality(metrics={}, issues=(f"recording unreadable: {_one_line(exc)}",))
    return quality.assess(
        decoded,
        simulated_seconds=simulated_seconds,
        map_expected=map_expected,
        host_expected=host_expected,
    )


def _ego_id(simulation: Simulation) -> int | None:
    ego = simulation.ego
    return simulation.world.actors[ego].id if ego is not None else None


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def _write_outputs(out: Path, report: RunReport, log: list[str]) -> None:
    out.mkdir(parents=True, exist_ok=True)
    outcome = report.outcome
    log.append(f"verdict {outcome.verdict} - {outcome.reason}")
    if outcome.ignored_elements:
        log.append(f"ignored: {', '.join(outcome.ignored_elements)}")
    for c in report.collisions:
        log.append(f"collision {c.first} & {c.second} at t={c.time:.2f} s")
    (out / "run.log").write_text("\n".join(log) + "\n", encoding="utf-8")
    result = outcome.to_json()
    result["artifacts"] = {**dict(outcome.artifacts), "log": str(out / "run.log")}
    if report.deviations:
        result["deviations"] = [d.describe() for d in report.deviations]
    (out / "result.json").write_text(
        json.dumps(result, indent=2, sort_keys=True) + "\n", encoding="utf-8"
    )


def run_many(requests: Sequence[RunRequest], *, jobs: int) -> Iterator[tuple[int, RunReport]]:
    """Run requests in ``jobs`` worker processes (spawned: one libsumo per process), yielding
    (index, report) as runs finish. ``jobs`` 1 runs in this process."""
    if jobs <= 1:
        for index, request in enumerate(requests):
            yield index, run_scenario(request)
        return
    context = multiprocessing.get_context("spawn")
    with context.Pool(processes=jobs) as pool:
        yield from pool.imap_unordered(_indexed, list(enumerate(requests)))


def _indexed(item: tuple[int, RunRequest]) -> tuple[int, RunReport]:
    index, request = item
    return index, run_scenario(request)
