"""``simtest-runner``: what a simulator pod runs.

The operator renders a run spec (:mod:`simtest_operator.render.runspecs`) into the pod's
``SIMTEST_RUN_SPEC`` variable. The runner fetches each scenario by its pinned URI (sha256
verified), runs it with :func:`simtest_operator.runner.execution.run_scenario` — simulation,
online evaluation, recording — writes the artifacts and the full result below the artifacts
folder, and leaves the compact result in the termination message (``/dev/termination-log``,
at most 4 KiB) where the operator reads it from the pod status.

Isolation ``Reuse``: one warm pod runs a queue of scenarios. Each scenario runs in a freshly
forked worker process; before each fork the runner verifies the reset — the parent never loaded
a simulator (no SUMO module in the parent process) and the worker of the previous scenario has
exited — so no state can leak from one scenario into the next. A scenario whose reset cannot be
verified is not run: it ends as ``Error`` (the operator retries it in a fresh pod).

Exit status: 0 once a result is written (the verdict is in the message, not the exit code); 2
for a malformed run spec. A crash leaves the traceback in the log, which the kubelet uses as the
termination message (``FallbackToLogsOnError``), so the operator still records an Error with it.
"""

from __future__ import annotations

import argparse
import dataclasses
import multiprocessing
import multiprocessing.connection
import os
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

from simtest_operator.api import converting
from simtest_operator.api.v1alpha1 import EvaluationSpec, SimulatorSettings, SutConfig
from simtest_operator.errors import RenderError, ScenarioError, SimtestError
from simtest_operator.render import RunSpec, ScenarioRef, messages, runspecs
from simtest_operator.runner import execution
from simtest_operator.scenarios import FetchContext, Locator, PinnedScenario
from simtest_operator.settings import Settings
from simtest_operator.verdicts import ScenarioOutcome, Verdict

TERMINATION_LOG = "/dev/termination-log"
SIMULATOR_MODULES = ("libsumo", "traci")
"""Modules whose presence in the parent process would mean simulator state could leak."""

RunOne = Callable[[execution.RunRequest], ScenarioOutcome]


def _run_one(request: execution.RunRequest) -> ScenarioOutcome:
    return execution.run_scenario(request).outcome


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Job:
    """A parsed run spec plus where things go."""

    spec: RunSpec
    artifacts: Path
    settings: Settings


def requests_for(job: Job, scenario: ScenarioRef, path: Path) -> execution.RunRequest:
    """The engine request of one scenario of the job."""
    spec = job.spec
    evaluation = EvaluationSpec.model_validate(dict(spec.evaluation))
    simulator = SimulatorSettings.model_validate(dict(spec.simulator))
    sut = SutConfig.model_validate(dict(spec.sut))
    return execution.RunRequest(
        scenario=path,
        nets_dir=job.settings.cache.nets,
        scenario_id=scenario.id,
        overrides=dict(scenario.overrides),
        sut=converting.sut(sut),
        criteria=converting.criteria(evaluation, scenario.id),
        simulation=converting.simulation(simulator),
        output_dir=job.artifacts / safe_name(scenario.id),
        record=simulator.record,
        wall_clock_limit=max(spec.timeout_seconds * 0.95, spec.timeout_seconds - 2.0),
    )


def safe_name(scenario_id: str) -> str:
    """A folder name for a scenario id (ids are paths; ``/`` and odd characters flattened)."""
    cleaned = "".join(c if c.isalnum() or c in "._-" else "_" for c in scenario_id)
    return cleaned.strip("._") or "scenario"


def run_job(
    job: Job, *, run_one: RunOne = _run_one, fork: bool | None = None
) -> list[ScenarioOutcome]:
    """Run every scenario of the job; never raises for scenario or simulator problems."""
    spec = job.spec
    locator = Locator(FetchContext(base_dir=Path("/"), cache_dir=job.settings.cache.sources))
    isolated = spec.isolation == "Reuse" and len(spec.scenarios) > 1 if fork is None else fork
    outcomes: list[ScenarioOutcome] = []
    for scenario in spec.scenarios:
        started = time.perf_counter()
        try:
            path = locator.locate(
                PinnedScenario(
                    id=scenario.id,
                    source=scenario.source,
                    sha256=scenario.sha256,
                    overrides=dict(scenario.overrides),
                )
            )
            request = requests_for(job, scenario, path)
            if isolated:
                problem = reset_problem()
                if problem is not None:
                    outcome = _failed(
                        scenario.id, Verdict.ERROR, f"reset not verified: {problem}", started
                    )
                else:
                    outcome = run_forked(run_one, request)
            else:
                outcome = run_one(request)
        except ScenarioError as exc:
            outcome = _failed(scenario.id, Verdict.INVALID, str(exc), started)
        except SimtestError as exc:
            outcome = _failed(scenario.id, Verdict.ERROR, str(exc), started)
        outcomes.append(_with_uris(outcome, job))
    return outcomes


def reset_problem() -> str | None:
    """Why the next scenario cannot be sure of a clean simulator, or None."""
    loaded = [m for m in SIMULATOR_MODULES if m in sys.modules]
    if loaded:
        return f"the parent process loaded {', '.join(loaded)}"
    children = multiprocessing.active_children()
    if children:
        return f"{len(children)} worker process(es) of earlier scenarios still alive"
    return None


def _child(
    conn: multiprocessing.connection.Connection, run_one: RunOne, request: execution.RunRequest
) -> None:
    try:
        conn.send(run_one(request).to_json())
    except BaseException as exc:  # the worker must always answer
        conn.send(
            {
                "scenarioId": request.scenario_id or "",
                "verdict": "Error",
                "reason": f"worker crashed: {exc}",
            }
        )
    finally:
        conn.close()


def run_forked(run_one: RunOne, request: execution.RunRequest) -> ScenarioOutcome:
    """Run one scenario in a fresh forked worker and wait for it to exit."""
    context = multiprocessing.get_context("fork")
    receiver, sender = context.Pipe(duplex=False)
    worker = context.Process(target=_child, args=(sender, run_one, request), daemon=True)
    started = time.perf_counter()
    worker.start()
    sender.close()
    try:
        data = receiver.recv()
    except EOFError:
        data = None
    worker.join()
    receiver.close()
    if data is None:
        return _failed(
            request.scenario_id or "",
            Verdict.ERROR,
            f"worker died (exit code {worker.exitcode})",
            started,
        )
    return ScenarioOutcome.from_json(data)


def _failed(scenario_id: str, verdict: Verdict, reason: str, started: float) -> ScenarioOutcome:
    return ScenarioOutcome(
        scenario_id=scenario_id,
        verdict=verdict,
        reason=" ".join(reason.split()),
        wall_seconds=time.perf_counter() - started,
    )


def _with_uris(outcome: ScenarioOutcome, job: Job) -> ScenarioOutcome:
    """Local artifact paths as URIs under the run spec's prefix; the result file added."""
    folder = job.artifacts / safe_name(outcome.scenario_id)
    artifacts = dict(outcome.artifacts)
    if (folder / "result.json").is_file():
        artifacts["result"] = str(folder / "result.json")
    if (folder / "run.log").is_file():
        artifacts.setdefault("log", str(folder / "run.log"))
    prefix = job.spec.artifacts_uri
    if prefix:
        root = str(job.artifacts)
        artifacts = {
            k: prefix + v[len(root) :] if v.startswith(root) else v for k, v in artifacts.items()
        }
    return dataclasses.replace(outcome, artifacts=artifacts)


def write_message(outcomes: Sequence[ScenarioOutcome], path: Path) -> str:
    """Write the compact result where the kubelet picks it up."""
    text = messages.encode(outcomes)
    path.write_text(text, encoding="utf-8")
    return text


def _arguments(argv: Sequence[str] | None, env: Mapping[str, str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="simtest-runner", description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--spec",
        default=env.get(runspecs.ENV_VAR),
        help=f"run spec JSON (default: ${runspecs.ENV_VAR})",
    )
    parser.add_argument(
        "--termination-log",
        type=Path,
        default=Path(env.get("SIMTEST_TERMINATION_LOG", TERMINATION_LOG)),
        help="where the compact result goes (default: /dev/termination-log)",
    )
    parser.add_argument(
        "--artifacts",
        type=Path,
        default=None,
        help="artifacts folder (default: the run spec's artifactsDir)",
    )
    return parser.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> None:
    """Console-script entry point."""
    env = os.environ
    args = _arguments(argv, env)
    if not args.spec:
        sys.stderr.write(f"simtest-runner: no run spec (set {runspecs.ENV_VAR} or pass --spec)\n")
        raise SystemExit(2)
    try:
        spec = RunSpec.loads(args.spec)
    except RenderError as exc:
        sys.stderr.write(f"simtest-runner: {exc}\n")
        raise SystemExit(2) from exc
    artifacts = args.artifacts or Path(spec.artifacts_dir)
    artifacts.mkdir(parents=True, exist_ok=True)
    job = Job(spec=spec, artifacts=artifacts, settings=Settings.from_env(env))
    outcomes = run_job(job)
    text = write_message(outcomes, args.termination_log)
    for outcome in outcomes:
        sys.stdout.write(f"{outcome.scenario_id}: {outcome.verdict.value} {outcome.reason}\n")
    sys.stdout.write(f"termination message: {len(text.encode())} bytes\n")
