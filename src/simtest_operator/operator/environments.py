"""SimEnvironment decisions: what its pod's state means, and what to do about it.

Pure: one environment's view, its pod's view (or None), the nodes and the clock in; an
:class:`Assessment` out. Every way a simulator pod can end maps to verdicts here:

* the runner's termination message -> the runner's verdicts (Passed, Failed, Timeout, Invalid...),
  with the entries' ``resultsStored: false`` (the results database did not take the row) kept;
* ``DeadlineExceeded`` (activeDeadlineSeconds) or the operator's backstop -> ``Timeout``;
* OOMKilled, eviction, deletion, a lost node, image errors, a crash without a result, Pending
  beyond ``pendingTimeoutSeconds`` -> ``Error`` with a reason (retried per spec as a new attempt).
"""

from __future__ import annotations

import dataclasses
import datetime
from collections.abc import Mapping

from simtest_operator.api.v1alpha1 import EnvironmentPhase, Timings
from simtest_operator.operator.observed import EnvironmentView, NodeView, PodView
from simtest_operator.operator.status.records import ResultRecord, clip
from simtest_operator.render import messages
from simtest_operator.verdicts import ScenarioOutcome, Verdict

IMAGE_ERRORS = frozenset(
    {
        "ErrImagePull",
        "ImagePullBackOff",
        "InvalidImageName",
        "ErrImageNeverPull",
        "CreateContainerConfigError",
        "CreateContainerError",
        "RunContainerError",
    }
)
"""Waiting reasons that mean the container will not start without someone fixing something."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Limits:
    """Time limits of one environment."""

    timeout_seconds: float
    """Per scenario (spec.execution.timeoutSeconds)."""
    pending_seconds: float
    """spec.execution.pendingTimeoutSeconds."""
    deadline_seconds: float
    """The pod's activeDeadlineSeconds."""
    backstop_grace: float = 30.0
    """How long past the deadline the operator waits for the kubelet before ending the run
    itself (fake nodes and lost kubelets never enforce the deadline)."""
    missing_grace: float = 10.0
    """How long a pod recorded as created may be absent from the cache before it counts as
    deleted (covers watch lag right after a restart)."""
    node_not_ready_grace: float = 60.0
    """How long the pod's node may be NotReady (its kubelet stopped reporting) before the run
    counts as lost: Error, the pod force-deleted, the scenarios retried."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Assessment:
    """What an environment is doing, and what the operator should do."""

    phase: EnvironmentPhase
    node: str | None
    timings: Timings
    results: tuple[ResultRecord, ...] | None
    """One record per scenario once the environment has ended; None while it runs."""
    reason: str = ""
    needs_pod: bool = False
    delete_pod: bool = False
    force_delete: bool = False
    """Delete with grace period 0 (the node is gone; nobody will confirm a graceful stop)."""
    wake_at: datetime.datetime | None = None
    """When a time limit next needs checking."""

    @property
    def ended(self) -> bool:
        """The environment has final (per-attempt) results."""
        return self.results is not None


def assess(
    env: EnvironmentView,
    pod: PodView | None,
    *,
    nodes: Mapping[str, NodeView] | None,
    now: datetime.datetime,
    limits: Limits,
    seen: bool = False,
) -> Assessment:
    """Judge one environment from its pod; ``seen``: this operator has watched the pod exist
    or be deleted (its absence is then a delete, even before the status recorded the pod)."""
    queued = env.status.timings.queued or env.created
    if env.finished:
        return Assessment(
            phase=EnvironmentPhase.FINISHED,
            node=env.status.node,
            timings=env.status.timings,
            results=env.results
            or failed_records(env, Verdict.ERROR, env.status.reason or "no result"),
            reason=env.status.reason,
            delete_pod=pod is not None and not pod.deleting,
        )
    if env.deleting:
        reason = f"SimEnvironment {env.name} was deleted before it finished"
        return Assessment(
            phase=EnvironmentPhase.FINISHED,
            node=env.status.node,
            timings=env.status.timings.model_copy(update={"finished": now}),
            results=failed_records(env, Verdict.ERROR, reason),
            reason=reason,
        )
    if pod is None:
        return _without_pod(env, now=now, limits=limits, queued=queued, seen=seen)
    timings = Timings(
        queued=queued,
        scheduled=pod.scheduled_at,
        started=pod.container.started_at or (pod.start_time if pod.container.state else None),
        finished=pod.container.finished_at,
    )
    node = pod.node_name
    if pod.terminated:
        end = timings.finished or now
        results, reason = _terminated(env, pod, timings=timings, end=end)
        finished_timings = timings.model_copy(update={"finished": end})
        return Assessment(
            phase=EnvironmentPhase.FINISHED,
            node=node,
            timings=finished_timings,
            results=_naming_the_sut(results, pod),
            reason=reason,
            delete_pod=False,
        )
    failure = _failure(env, pod, nodes=nodes, now=now, limits=limits, queued=queued)
    if failure is not None:
        verdict, reason, force = failure
        return Assessment(
            phase=EnvironmentPhase.FINISHED,
            node=node,
            timings=timings.model_copy(update={"finished": now}),
            results=_naming_the_sut(
                failed_records(env, verdict, reason, started=timings.started, end=now), pod
            ),
            reason=reason,
            delete_pod=not pod.deleting or force,
            force_delete=force,
        )
    running = pod.container.state == "running"
    phase = (
        EnvironmentPhase.RUNNING
        if running
        else EnvironmentPhase.SCHEDULED
        if node
        else EnvironmentPhase.PROVISIONING
    )
    return Assessment(
        phase=phase,
        node=node,
        timings=timings,
        results=None,
        wake_at=_next_check(pod, timings, limits=limits, queued=queued, nodes=nodes),
    )


def _without_pod(
    env: EnvironmentView,
    *,
    now: datetime.datetime,
    limits: Limits,
    queued: datetime.datetime | None,
    seen: bool,
) -> Assessment:
    timings = env.status.timings.model_copy(update={"queued": queued})
    if env.provisioned_at is None and env.status.pod is None:
        return Assessment(
            phase=EnvironmentPhase.PENDING, node=None, timings=timings, results=None, needs_pod=True
        )
    since = env.provisioned_at or queued or now
    recorded = env.status.timings
    seen = seen or env.status.node is not None or recorded.started is not None
    seen = seen or recorded.scheduled is not None
    # A pod the cache never showed may exist behind a lagging watch (a starved operator under
    # load: 10,000 scenarios on 2 busy cores lost 6 running pods to a 10 s grace). Until the
    # cache has shown it once, its absence is no evidence of a delete: it gets the time a
    # Pending pod gets to start.
    grace = limits.missing_grace if seen else max(limits.missing_grace, limits.pending_seconds)
    grace_end = since + datetime.timedelta(seconds=grace)
    if now < grace_end:
        return Assessment(
            phase=env.status.phase,
            node=env.status.node,
            timings=timings,
            results=None,
            wake_at=grace_end,
        )
    name = env.status.pod or env.name
    reason = (
        f"simulator pod {name} disappeared before it finished (deleted)"
        if seen
        else f"simulator pod {name} never appeared in {grace:.0f}s after it was created "
        "(pendingTimeoutSeconds; deleted?)"
    )
    return Assessment(
        phase=EnvironmentPhase.FINISHED,
        node=env.status.node,
        timings=timings.model_copy(update={"finished": now}),
        results=failed_records(env, Verdict.ERROR, reason, started=timings.started, end=now),
        reason=reason,
    )


def _failure(
    env: EnvironmentView,
    pod: PodView,
    *,
    nodes: Mapping[str, NodeView] | None,
    now: datetime.datetime,
    limits: Limits,
    queued: datetime.datetime | None,
) -> tuple[Verdict, str, bool] | None:
    """An ending the pod itself does not report: (verdict, reason, force delete) or None."""
    if pod.node_name and nodes is not None and pod.node_name not in nodes:
        return Verdict.ERROR, f"node {pod.node_name} was lost while the pod ran", True
    silent = _node_silent_since(pod, nodes)
    if silent is not None and (now - silent).total_seconds() >= limits.node_not_ready_grace:
        # Nobody will finish or report this pod: a graceful delete would wait for the kubelet.
        return (
            Verdict.ERROR,
            f"node {pod.node_name} stopped reporting (NotReady since "
            f"{silent:%H:%M:%S}) while the pod ran",
            True,
        )
    if pod.deleting:
        cause = f": {pod.disruption}" if pod.disruption else ""
        return (
            Verdict.ERROR,
            f"simulator pod {pod.name} was deleted before it finished{cause}",
            False,
        )
    waiting = pod.container
    if waiting.state == "waiting" and waiting.reason in IMAGE_ERRORS:
        detail = f": {waiting.message}" if waiting.message else ""
        return Verdict.ERROR, f"container cannot start ({waiting.reason}){detail}", False
    started = pod.container.started_at
    if started is None and pod.container.state != "running":
        since = pod.created or queued or now
        waited = (now - since).total_seconds()
        if waited >= limits.pending_seconds:
            why = f" ({pod.unschedulable})" if pod.unschedulable else ""
            return (
                Verdict.ERROR,
                f"pod still Pending after {waited:.0f}s (pendingTimeoutSeconds "
                f"{limits.pending_seconds:.0f}){why}",
                False,
            )
        return None
    begin = started or pod.start_time or since_or(pod.created, now)
    ran = (now - begin).total_seconds()
    if ran >= limits.deadline_seconds + limits.backstop_grace:
        return (
            Verdict.TIMEOUT,
            f"ran {ran:.0f}s, past the {limits.deadline_seconds:.0f}s deadline "
            "(timeoutSeconds); stopped by the operator",
            False,
        )
    return None


def since_or(value: datetime.datetime | None, default: datetime.datetime) -> datetime.datetime:
    """``value`` unless None."""
    return value if value is not None else default


def _node_silent_since(
    pod: PodView, nodes: Mapping[str, NodeView] | None
) -> datetime.datetime | None:
    """Since when the pod's node has been NotReady, if it is."""
    node = nodes.get(pod.node_name) if pod.node_name and nodes is not None else None
    return node.not_ready_since if node is not None and not node.ready else None


def node_gone(pod: PodView, nodes: Mapping[str, NodeView] | None) -> bool:
    """Whether no kubelet will stop the pod: its node was deleted or is NotReady. Such a pod is
    deleted without a grace period, or its object would wait for a kubelet that never comes."""
    if not pod.node_name or nodes is None:
        return False
    return pod.node_name not in nodes or _node_silent_since(pod, nodes) is not None


def _next_check(
    pod: PodView,
    timings: Timings,
    *,
    limits: Limits,
    queued: datetime.datetime | None,
    nodes: Mapping[str, NodeView] | None = None,
) -> datetime.datetime | None:
    silent = _node_silent_since(pod, nodes)
    if silent is not None:
        return silent + datetime.timedelta(seconds=limits.node_not_ready_grace)
    if timings.started is None and pod.container.state != "running":
        since = pod.created or queued
        return since + datetime.timedelta(seconds=limits.pending_seconds) if since else None
    begin = timings.started or pod.start_time
    if begin is None:
        return None
    return begin + datetime.timedelta(seconds=limits.deadline_seconds + limits.backstop_grace)


def _naming_the_sut(records: tuple[ResultRecord, ...], pod: PodView) -> tuple[ResultRecord, ...]:
    """The pod's records with the SUT image its kubelet ran: only the pod status knows it (the
    runner inside sees a TCP peer), and a tag can move between attempts."""
    if not pod.sut_image_id:
        return records
    return tuple(
        r if r.sut_image_id else dataclasses.replace(r, sut_image_id=pod.sut_image_id)
        for r in records
    )


def _terminated(
    env: EnvironmentView, pod: PodView, *, timings: Timings, end: datetime.datetime
) -> tuple[tuple[ResultRecord, ...], str]:
    container = pod.container
    exit_text = (
        f"exit code {container.exit_code}" if container.exit_code is not None else "no exit code"
    )
    default_id = env.scenarios[0].id if len(env.scenarios) == 1 else None
    try:
        outcomes = messages.decode(container.message, default_id=default_id)
    except messages.MessageError:
        outcomes = ()
    # The runner rewrites its message after every scenario, so whatever killed the pod, the
    # scenarios that finished before keep their verdicts; the pod's fate is the verdict of the
    # one it interrupted, and the ones it never started are Error (run again elsewhere).
    stopped = messages.flagged(container.message, messages.STOPPED, True, default_id=default_id)
    finished = tuple(o for o in outcomes if o.scenario_id not in stopped)
    cut: tuple[Verdict, str] | None = None
    if pod.reason == "DeadlineExceeded":
        reason = clip(f"exceeded its deadline (activeDeadlineSeconds): {pod.message}".rstrip(": "))
        cut = (Verdict.TIMEOUT, reason)
    elif pod.reason == "Evicted":
        cut = (Verdict.ERROR, clip(f"evicted: {pod.message}".rstrip(": ")))
    elif container.reason == "OOMKilled":
        reason = f"simulator killed for exceeding its memory limit (OOMKilled, {exit_text})"
        cut = (Verdict.ERROR, reason)
    if cut is not None:
        return _cut_short(env, finished, cut, started=timings.started, end=end), cut[1]
    if outcomes:
        unstored = messages.flagged(
            container.message, messages.RESULTS_STORED, False, default_id=default_id
        )
        ended = f"{exit_text}, {container.reason}" if container.reason else exit_text
        return _from_outcomes(
            env, outcomes, unstored, ended=ended, started=timings.started, end=end
        )
    tail = (
        clip(container.message.strip().splitlines()[-1], 300) if container.message.strip() else ""
    )
    if container.exit_code == 0 and not tail:
        reason = "runner finished without writing a result (empty termination message)"
    else:
        cause = f" ({container.reason})" if container.reason else ""
        reason = f"runner ended with {exit_text}{cause} and no result" + (
            f": {tail}" if tail else ""
        )
    return failed_records(env, Verdict.ERROR, reason, started=timings.started, end=end), reason


def _cut_short(
    env: EnvironmentView,
    finished: tuple[ScenarioOutcome, ...],
    cut: tuple[Verdict, str],
    *,
    started: datetime.datetime | None,
    end: datetime.datetime,
) -> tuple[ResultRecord, ...]:
    """Records of a pod that was killed: finished scenarios kept, the interrupted one gets the
    pod's verdict, the rest are Error (not run)."""
    by_id = {o.scenario_id: o for o in finished}
    verdict, reason = cut
    records: list[ResultRecord] = []
    interrupted = False
    for scenario in env.scenarios:
        outcome = by_id.get(scenario.id)
        if outcome is not None:
            duration = outcome.wall_seconds if outcome.wall_seconds > 0 else 0.0
            records.append(
                ResultRecord.from_outcome(outcome, attempts=env.attempt, duration=duration)
            )
        elif not interrupted:
            interrupted = True
            records.append(
                ResultRecord(
                    id=scenario.id,
                    verdict=verdict,
                    reason=clip(reason),
                    duration_seconds=_elapsed(started, end) - sum(o.wall_seconds for o in finished),
                    attempts=env.attempt,
                )
            )
        else:
            records.append(
                ResultRecord(
                    id=scenario.id,
                    verdict=Verdict.ERROR,
                    reason=clip(f"not run: the warm simulator was stopped before it ({reason})"),
                    attempts=env.attempt,
                )
            )
    return tuple(records)


def _from_outcomes(
    env: EnvironmentView,
    outcomes: tuple[ScenarioOutcome, ...],
    unstored: frozenset[str] = frozenset(),
    *,
    ended: str,
    started: datetime.datetime | None,
    end: datetime.datetime,
) -> tuple[tuple[ResultRecord, ...], str]:
    by_id = {o.scenario_id: o for o in outcomes}
    records = []
    fallback = _elapsed(started, end)
    for scenario in env.scenarios:
        outcome = by_id.get(scenario.id)
        if outcome is None:
            records.append(
                ResultRecord(
                    id=scenario.id,
                    verdict=Verdict.ERROR,
                    reason=f"the warm simulator ended ({ended}) before running this scenario",
                    attempts=env.attempt,
                )
            )
            continue
        duration = outcome.wall_seconds if outcome.wall_seconds > 0 else fallback
        record = ResultRecord.from_outcome(outcome, attempts=env.attempt, duration=duration)
        if scenario.id in unstored:
            record = dataclasses.replace(record, results_stored=False)
        records.append(record)
    last = records[-1]
    return tuple(records), last.reason


def _elapsed(started: datetime.datetime | None, end: datetime.datetime) -> float:
    return max((end - started).total_seconds(), 0.0) if started else 0.0


def failed_records(
    env: EnvironmentView,
    verdict: Verdict,
    reason: str,
    *,
    started: datetime.datetime | None = None,
    end: datetime.datetime | None = None,
) -> tuple[ResultRecord, ...]:
    """The same non-runner verdict for every scenario of the environment that has none yet."""
    known = {r.id: r for r in env.results}
    duration = _elapsed(started, end) if end is not None else 0.0
    return tuple(
        known.get(s.id)
        or ResultRecord(
            id=s.id,
            verdict=verdict,
            reason=clip(reason),
            duration_seconds=duration,
            attempts=env.attempt,
        )
        for s in env.scenarios
    )
