"""``simtest-runner``: what a simulator pod runs.

The operator renders a run spec (:mod:`simtest_operator.render.runspecs`) into the pod's
``SIMTEST_RUN_SPEC`` variable. The runner fetches each scenario by its pinned URI (sha256
verified), runs it with :func:`simtest_operator.runner.scenario_execution.run_scenario` —
simulation, online evaluation, recording — writes the artifacts and the full result below the
artifacts folder, and leaves the compact result in the termination message
(``/dev/termination-log``, at most 4 KiB) where the operator reads it from the pod status.

Isolation ``Reuse``: one warm pod runs a queue of scenarios. The runner loads libsumo and reads
the reproducibility record once (most of a simulator's start-up) and runs each scenario in a
worker process forked from itself, so every scenario starts warm and none pays for them again.
Before each fork the runner verifies the reset — the parent has no simulation loaded (it loads
the engine, it never runs it) and the worker of the previous scenario has exited — so no state
can leak from one scenario into the next. A scenario whose reset cannot be verified is not run:
it ends as ``Error`` (the operator retries it in a fresh pod).

After the run the results are delivered (:mod:`simtest_operator.runner.delivering`): with an
``s3://`` artifacts URI the files are uploaded (endpoint and keys from ``AWS_ENDPOINT_URL_S3`` or
``AWS_ENDPOINT_URL``, ``AWS_ACCESS_KEY_ID``, ``AWS_SECRET_ACCESS_KEY``), and with
``SIMTEST_RESULTS_DSN`` plus ``SIMTEST_RESULTS_RUN_KEY`` every attempt becomes a row of the
results database; with ``keepRecordings: false`` in the run spec each recording is deleted
before that (metrics computed, digest kept). Neither can change a verdict: the termination
message stays the source of truth, an entry whose row was not stored says
``"resultsStored": false``.

Exit status: 0 once a result is written (the verdict is in the message, not the exit code); 2
for a malformed run spec. A crash leaves the traceback in the log, which the kubelet uses as the
termination message (``FallbackToLogsOnError``), so the operator still records an Error with it.
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import multiprocessing
import multiprocessing.connection
import os
import signal
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from collections.abc import Set as AbstractSet
from pathlib import Path
from typing import TYPE_CHECKING

from simtest_operator import provenance
from simtest_operator.api import converting
from simtest_operator.api.v1alpha1 import EvaluationSpec, SimulatorSettings, SutConfig
from simtest_operator.errors import (
    RenderError,
    ResultsError,
    ScenarioError,
    SimtestError,
    SourceError,
)
from simtest_operator.openscenario import LoadOptions
from simtest_operator.render import RunSpec, ScenarioRef, messages, runspecs
from simtest_operator.render.inputs import STARTUP_ALLOWANCE_SECONDS
from simtest_operator.runner import scenario_execution, suts
from simtest_operator.scenarios import (
    FetchContext,
    Locator,
    MountedConfigMaps,
    PinnedScenario,
    SecretProvider,
    SecretRef,
    uris,
)
from simtest_operator.settings import RESULTS_RUN_KEY, Settings
from simtest_operator.sim import sumo
from simtest_operator.verdicts import ScenarioOutcome, Verdict

if TYPE_CHECKING:
    # Delivery (the results database, S3) is imported once the runs are over: psycopg (0.03-0.1 s
    # of imports) stays off the path to the first simulation step.
    from simtest_operator.results import uploading
    from simtest_operator.runner import delivering

TERMINATION_LOG = "/dev/termination-log"
CONFIG_MAP_ROOT = Path(runspecs.CONFIG_MAP_DIR)
"""Where the operator mounts the ConfigMaps the pod's scenarios name."""
DEADLINE_MARGIN_SECONDS = 10.0
"""Time kept free before the pod's activeDeadlineSeconds (pod start precedes the runner's)."""

RunOne = Callable[[scenario_execution.RunRequest], ScenarioOutcome]


def _run_one(request: scenario_execution.RunRequest) -> ScenarioOutcome:
    return scenario_execution.run_scenario(request).outcome


class Terminated(BaseException):
    """SIGTERM arrived: the pod is being deleted (or its node drained) while scenarios ran.

    A BaseException, like KeyboardInterrupt, so that no ``except Exception`` inside the
    simulation turns it into a verdict of the scenario: it belongs to the environment.
    """


def _raise_terminated(signum: int, frame: object) -> None:
    raise Terminated


TERMINATED_REASON = "stopped: the pod was terminated (SIGTERM) while this scenario ran"
NOT_STARTED_REASON = "not run: the pod was terminated (SIGTERM) before this scenario started"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Job:
    """A parsed run spec plus where things go."""

    spec: RunSpec
    artifacts: Path
    settings: Settings


def requests_for(job: Job, scenario: ScenarioRef, path: Path) -> scenario_execution.RunRequest:
    """The engine request of one scenario of the job."""
    spec = job.spec
    evaluation = EvaluationSpec.model_validate(dict(spec.evaluation))
    simulator = SimulatorSettings.model_validate(dict(spec.simulator))
    sut = SutConfig.model_validate(dict(spec.sut))
    return scenario_execution.RunRequest(
        scenario=path,
        nets_dir=job.settings.cache.nets,
        scenario_id=scenario.id,
        overrides=dict(scenario.overrides),
        sut=suts.reached_here(converting.sut(sut), job.settings),
        criteria=converting.criteria(evaluation, scenario.id),
        simulation=converting.simulation(simulator),
        output_dir=job.artifacts / safe_name(scenario.id),
        record=simulator.record,
        wall_clock_limit=scenario_execution.soft_limit(spec.timeout_seconds),
        loading=LoadOptions(
            source_root=uris.source_root(path, scenario.source), maps=job.settings.maps
        ),
    )


def safe_name(scenario_id: str) -> str:
    """A folder name for a scenario id (ids are paths; ``/`` and odd characters flattened)."""
    cleaned = "".join(c if c.isalnum() or c in "._-" else "_" for c in scenario_id)
    return cleaned.strip("._") or "scenario"


def run_job(
    job: Job,
    *,
    run_one: RunOne = _run_one,
    fork: bool | None = None,
    progress: Callable[[Sequence[delivering.Attempt]], None] | None = None,
) -> list[delivering.Attempt]:
    """Run every scenario of the job; never raises for scenario or simulator problems.

    ``progress`` gets the attempts so far after each scenario: the entry point rewrites the
    termination message there, so a pod killed mid-queue still reports what it finished.
    """
    spec = job.spec
    locator = locator_for(
        spec,
        cache=job.settings.cache.sources,
        tokens=job.settings.source_tokens,
        config_maps=CONFIG_MAP_ROOT,
    )
    isolated = spec.isolation == "Reuse" and len(spec.scenarios) > 1 if fork is None else fork
    if isolated and run_one is _run_one:
        warm_up()
    attempts: list[delivering.Attempt] = []
    for index, scenario in enumerate(spec.scenarios):
        started = time.perf_counter()
        path: Path | None = None
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
        except SourceError as exc:
            # The operator resolved and pinned this source: if the pod cannot fetch it, the
            # environment is at fault (a path source without the scenario volume, a network
            # policy, a moved file), never the scenario, so Error (retried), not Invalid.
            reason = f"the pod cannot fetch the pinned scenario: {exc}"
            if scenario.source.startswith("file://"):
                reason += (
                    " (path sources need the scenario volume: SIMTEST_OPERATOR_SCENARIO_CLAIM)"
                )
            outcome = _failed(scenario.id, Verdict.ERROR, reason, started)
        except ScenarioError as exc:
            outcome = _failed(scenario.id, Verdict.INVALID, str(exc), started)
        except SimtestError as exc:
            outcome = _failed(scenario.id, Verdict.ERROR, str(exc), started)
        except Terminated:
            # Keep what finished; the interrupted and the unstarted scenarios are Error, so the
            # operator runs them again elsewhere. Nothing here may take long: the kubelet kills
            # the container when the grace period ends.
            attempts.append(
                _attempt(
                    scenario,
                    path,
                    _failed(scenario.id, Verdict.ERROR, TERMINATED_REASON, started),
                    job,
                    stopped=True,
                )
            )
            attempts.extend(
                _attempt(
                    rest,
                    None,
                    _failed(rest.id, Verdict.ERROR, NOT_STARTED_REASON, started),
                    job,
                    stopped=True,
                )
                for rest in spec.scenarios[index + 1 :]
            )
            return attempts
        attempts.append(_attempt(scenario, path, outcome, job))
        if progress is not None:
            progress(attempts)
    return attempts


def locator_for(
    spec: RunSpec, *, cache: Path, tokens: Mapping[str, str], config_maps: Path
) -> Locator:
    """The pod's Locator: ConfigMaps from the folders the operator mounts, the run spec's
    databases, their ``tokens`` from the ``secretKeyRef`` variables the template sets
    (:func:`runspecs.secret_variables`, read into ``Settings.source_tokens``). The pod has no API
    access: nothing is read from the cluster here."""
    ctx = FetchContext(
        base_dir=Path("/"),
        cache_dir=cache,
        config_maps=MountedConfigMaps(config_maps),
        secrets=pod_secrets(spec, tokens),
    )
    return Locator(ctx, graphql_sources=spec.databases)


def pod_secrets(spec: RunSpec, tokens: Mapping[str, str]) -> SecretProvider:
    """Secret values from the container's token variables (by name); a missing one is a
    SourceError (Error)."""
    variables = runspecs.secret_variables(spec.databases)

    def provide(ref: SecretRef) -> str:
        variable = variables.get(ref)
        if variable is None:
            raise SourceError(f"Secret {ref.name}/{ref.key} is not one the run spec lists")
        value = tokens.get(variable, "").strip()
        if not value:
            raise SourceError(
                f"Secret {ref.name}/{ref.key} is not available in the pod ({variable} is unset: "
                "the Secret or its key is missing)"
            )
        return value

    return provide


def warm_up() -> None:
    """Pay once per pod what every scenario needs before its first step, before the forks."""
    sumo.preload()  # libsumo: a forked scenario starts with it loaded
    provenance.versions()  # computed once per process: the forks inherit it
    gc.freeze()  # the forks' collector neither scans nor copies the warm parent's objects


def reset_problem() -> str | None:
    """Why the next scenario cannot be sure of a clean simulator, or None."""
    if sumo.running():
        return "the parent process has a SUMO simulation loaded"
    children = multiprocessing.active_children()
    if children:
        return f"{len(children)} worker process(es) of earlier scenarios still alive"
    return None


def _child(
    conn: multiprocessing.connection.Connection,
    run_one: RunOne,
    request: scenario_execution.RunRequest,
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


def run_forked(run_one: RunOne, request: scenario_execution.RunRequest) -> ScenarioOutcome:
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
    except Terminated:
        worker.kill()  # the fork does not get the pod's SIGTERM: stop it with the parent
        worker.join()
        raise
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


def _attempt(
    scenario: ScenarioRef,
    path: Path | None,
    outcome: ScenarioOutcome,
    job: Job,
    *,
    stopped: bool = False,
) -> delivering.Attempt:
    """The attempt with the pod's attempt number and every local artifact (result file added)."""
    from simtest_operator.runner import delivering

    folder = job.artifacts / safe_name(scenario.id)
    artifacts = dict(outcome.artifacts)
    if (folder / "result.json").is_file():
        artifacts["result"] = str(folder / "result.json")
    if (folder / "run.log").is_file():
        artifacts.setdefault("log", str(folder / "run.log"))
    outcome = dataclasses.replace(outcome, artifacts=artifacts, attempts=job.spec.attempt)
    return delivering.Attempt(
        scenario=scenario, path=path, outcome=outcome, folder=folder, stopped=stopped
    )


def _report(attempts: Sequence[delivering.Attempt], termination_log: Path) -> None:
    """After each scenario: its line in the log and every verdict so far in the message."""
    outcome = attempts[-1].outcome
    sys.stdout.write(
        f"finished {outcome.scenario_id}: {outcome.verdict.value} ({outcome.wall_seconds:.2f} s)\n"
    )
    sys.stdout.flush()
    write_message([a.outcome for a in attempts], termination_log)


def write_message(
    outcomes: Sequence[ScenarioOutcome],
    path: Path,
    *,
    unstored: AbstractSet[str] = frozenset(),
    stopped: AbstractSet[str] = frozenset(),
) -> str:
    """Write the compact result where the kubelet picks it up, flagging entries not stored and
    scenarios SIGTERM stopped.

    One ``write`` of the whole text over the old one: the runner rewrites the message after every
    scenario, and the kubelet copies whatever the file holds when the container ends, however it
    ends (a kill, the OOM killer, the deadline).
    """
    flags: dict[str, dict[str, bool]] = {}
    for scenario_id in unstored:
        flags.setdefault(scenario_id, {})[messages.RESULTS_STORED] = False
    for scenario_id in stopped:
        flags.setdefault(scenario_id, {})[messages.STOPPED] = True
    text = messages.encode_flagged(outcomes, flags)
    path.write_text(text, encoding="utf-8")
    return text


def deliverer_for(
    job: Job, env: Mapping[str, str], *, run_key: str | None, deadline: float | None
) -> delivering.Deliverer:
    """The pod's deliverer from the run spec, the settings (the results database and run key)
    and the container environment (the S3 credentials)."""
    from simtest_operator import results
    from simtest_operator.results import uploading
    from simtest_operator.runner import delivering

    spec = job.spec
    deliverer = delivering.Deliverer(
        campaign=spec.campaign,
        artifacts_root=job.artifacts,
        uri_prefix=spec.artifacts_uri,
        sut={k: str(v) for k, v in spec.sut.items() if k in ("name", "version")},
        remaining=None if deadline is None else (lambda: deadline - time.monotonic()),
        keep_recordings=spec.keep_recordings,
    )
    if spec.artifacts_uri.startswith(uploading.SCHEME):
        try:
            deliverer.uploader = uploading.Uploader(
                uploading.S3Location.parse(spec.artifacts_uri),
                s3_credentials(env),
                remaining=deliverer.remaining,
            )
        except ResultsError as exc:
            deliverer.upload_problem = str(exc)
    dsn = job.settings.results.dsn
    key = (run_key or job.settings.results.run_key).strip()
    if dsn and key:
        deliverer.results_target = delivering.ResultsTarget(dsn=dsn, run_key=results.RunKey(key))
    elif dsn:
        deliverer.results_problem = f"no run key (set {RESULTS_RUN_KEY})"
    return deliverer


def s3_credentials(env: Mapping[str, str]) -> uploading.S3Credentials:
    """Endpoint and keys from the standard ``AWS_*`` variables; missing ones are an error."""
    from simtest_operator.results import uploading

    endpoint = env.get("AWS_ENDPOINT_URL_S3") or env.get("AWS_ENDPOINT_URL") or ""
    missing = [
        name
        for name, value in (
            ("AWS_ENDPOINT_URL_S3 or AWS_ENDPOINT_URL", endpoint),
            ("AWS_ACCESS_KEY_ID", env.get("AWS_ACCESS_KEY_ID")),
            ("AWS_SECRET_ACCESS_KEY", env.get("AWS_SECRET_ACCESS_KEY")),
        )
        if not value
    ]
    if missing:
        raise ResultsError(f"the pod has no {', '.join(missing)}")
    return uploading.S3Credentials(
        endpoint=endpoint,
        access_key_id=env["AWS_ACCESS_KEY_ID"],
        secret_access_key=env["AWS_SECRET_ACCESS_KEY"],
        session_token=env.get("AWS_SESSION_TOKEN", ""),
        region=env.get("AWS_REGION") or env.get("AWS_DEFAULT_REGION") or "us-east-1",
    )


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
        "--run-key",
        default=None,
        help=f"results run key (default: ${RESULTS_RUN_KEY})",
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
    begun = time.monotonic()
    deadline = (
        begun
        + spec.timeout_seconds * len(spec.scenarios)
        + STARTUP_ALLOWANCE_SECONDS
        - DEADLINE_MARGIN_SECONDS
    )
    artifacts = args.artifacts or Path(spec.artifacts_dir)
    artifacts.mkdir(parents=True, exist_ok=True)
    job = Job(spec=spec, artifacts=artifacts, settings=Settings.from_env(env))
    signal.signal(signal.SIGTERM, _raise_terminated)
    attempts = run_job(job, progress=lambda done: _report(done, args.termination_log))
    # Past the runs a second SIGTERM ends the process at once: the verdicts are written next.
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    stopped = frozenset(a.scenario.id for a in attempts if a.stopped)
    # The verdicts first: whatever happens while delivering, the kubelet finds them.
    write_message([a.outcome for a in attempts], args.termination_log, stopped=stopped)
    deliverer = deliverer_for(job, env, run_key=args.run_key, deadline=deadline)
    delivered = deliverer.deliver(attempts)
    for note in delivered.notes:
        sys.stderr.write(f"simtest-runner: {note}\n")
    text = write_message(
        delivered.outcomes, args.termination_log, unstored=delivered.unstored, stopped=stopped
    )
    for outcome in delivered.outcomes:
        sys.stdout.write(f"{outcome.scenario_id}: {outcome.verdict.value} {outcome.reason}\n")
    sys.stdout.write(f"termination message: {len(text.encode())} bytes\n")
