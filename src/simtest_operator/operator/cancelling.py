"""Cancellation: when a campaign stops for good, and what that means for each of its scenarios.

Two causes, one outcome, as with a Kubernetes Job or an Argo Workflow: ``spec.cancel`` (someone
says stop) and ``spec.activeDeadlineSeconds`` (the whole campaign ran too long, counted from
``status.startTime``). Either way nothing new starts, attempts in flight end ``Skipped`` (their
pods are deleted once that is recorded), every scenario not started ends ``Skipped``, and the
campaign's phase becomes ``Cancelled`` — ``Complete=True`` with reason ``Cancelled`` or
``DeadlineExceeded`` once every verdict is recorded. Verdicts already known stand.

``suspend`` is the resumable pause; cancellation is final. The decision is kept in the campaign
status (phase ``Cancelled``, the cause as the ``Running`` condition's reason), so setting
``cancel`` back to false, or raising the deadline afterwards, changes nothing — and a restarted
operator re-derives the same outcome from spec, status and children.

Scenarios of batches that were never created are not given objects just to say "not run": they
count as ``skipped`` in the campaign counters and stay listed in the frozen-list ConfigMap.
"""

from __future__ import annotations

import dataclasses
import datetime
import enum
from collections.abc import Collection, Sequence

from simtest_operator.api.v1alpha1 import EnvironmentPhase, TestCampaignSpec, TestCampaignStatus
from simtest_operator.operator.batches import Layout, ScenarioState, State
from simtest_operator.operator.environments import Assessment
from simtest_operator.operator.observed import EnvironmentView
from simtest_operator.operator.status import conditions, reading
from simtest_operator.operator.status.records import ResultRecord, clip
from simtest_operator.verdicts import Verdict

CANCELLED_PHASE = "Cancelled"
FINISHED_PHASES = frozenset({"Succeeded", "Failed", "Error"})
"""A campaign that ended on its own is never cancelled afterwards."""


class Reason(enum.StrEnum):
    """Why a campaign was cancelled (the reason of its Running and Complete conditions)."""

    CANCELLED = "Cancelled"
    """``spec.cancel`` was set."""
    DEADLINE_EXCEEDED = "DeadlineExceeded"
    """``spec.activeDeadlineSeconds`` passed since ``status.startTime``."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Cancellation:
    """A campaign's cancellation: its cause and the one-line message conditions and events say."""

    reason: Reason
    message: str

    @property
    def skip_reason(self) -> str:
        """The ``reason`` of each Skipped result."""
        if self.reason is Reason.DEADLINE_EXCEEDED:
            return f"cancelled: {self.message}"
        return "cancelled"


def deadline(spec: TestCampaignSpec, status: TestCampaignStatus) -> datetime.datetime | None:
    """When ``activeDeadlineSeconds`` runs out (None without a limit or before the start)."""
    start = status.start_time
    if spec.active_deadline_seconds is None or start is None:
        return None
    return start + datetime.timedelta(seconds=spec.active_deadline_seconds)


def recorded(status: TestCampaignStatus) -> Cancellation | None:
    """The cancellation the status already records (None when it records none)."""
    if status.phase != CANCELLED_PHASE:
        return None
    running = reading.condition(status, "Running")
    try:
        reason = Reason(running.reason if running is not None else "")
    except ValueError:
        reason = Reason.CANCELLED
    message = running.message if running is not None else ""
    return Cancellation(reason=reason, message=message or "cancelled")


def decide(
    spec: TestCampaignSpec, status: TestCampaignStatus, *, now: datetime.datetime
) -> Cancellation | None:
    """Whether the campaign is cancelled, and why: once recorded always; otherwise by
    ``spec.cancel`` or the deadline, unless the campaign has already ended on its own."""
    kept = recorded(status)
    if kept is not None:
        return kept
    if status.phase in FINISHED_PHASES:
        return None
    if spec.cancel:
        return Cancellation(reason=Reason.CANCELLED, message="spec.cancel is true")
    limit = deadline(spec, status)
    if limit is not None and status.start_time is not None and now >= limit:
        return Cancellation(
            reason=Reason.DEADLINE_EXCEEDED,
            message=f"activeDeadlineSeconds ({spec.active_deadline_seconds} s) exceeded "
            f"since the start at {conditions.rfc3339(status.start_time)}",
        )
    return None


def assessment(
    env: EnvironmentView,
    judged: Assessment,
    cancellation: Cancellation,
    *,
    now: datetime.datetime,
) -> Assessment:
    """An environment's assessment under cancellation.

    One whose verdicts are recorded keeps them. Otherwise the attempt ends now: every scenario
    without a verdict, and every ``Error`` (deleting the pod causes one, so it cannot be told
    from a real one), becomes ``Skipped``; a verdict the runner delivered stands. The planner
    records this in the environment's status and deletes the pod in the next step, as always.
    """
    if env.finished:
        return judged
    reason = clip(cancellation.skip_reason)
    started = judged.timings.started
    duration = max((now - started).total_seconds(), 0.0) if started else 0.0
    if judged.results is None:
        results = tuple(
            ResultRecord(
                id=scenario.id,
                verdict=Verdict.SKIPPED,
                reason=reason,
                duration_seconds=duration,
                attempts=env.attempt,
            )
            for scenario in env.scenarios
        )
    elif any(r.verdict is Verdict.ERROR for r in judged.results):
        results = tuple(
            dataclasses.replace(r, verdict=Verdict.SKIPPED, reason=reason)
            if r.verdict is Verdict.ERROR
            else r
            for r in judged.results
        )
    else:
        return judged
    return dataclasses.replace(
        judged,
        phase=EnvironmentPhase.FINISHED,
        timings=judged.timings.model_copy(update={"finished": judged.timings.finished or now}),
        results=results,
        reason=reason,
        needs_pod=False,
        wake_at=None,
    )


def states(
    current: Sequence[ScenarioState],
    layout: Layout,
    cancellation: Cancellation,
    *,
    batches: Collection[int],
) -> tuple[ScenarioState, ...]:
    """Scenario states under cancellation: whatever had not started (or waited for a retry)
    ends Skipped — to be folded into its batch when the batch exists, else final at once."""
    out = []
    for state in current:
        if state.state not in (State.PENDING, State.RETRY):
            out.append(state)
            continue
        reason = cancellation.skip_reason
        if state.state is State.RETRY and state.result is not None:
            reason = (
                f"{reason}; attempt {state.attempt} had ended with Error: {state.result.reason}"
            )
        record = ResultRecord(
            id=state.id,
            verdict=Verdict.SKIPPED,
            reason=clip(reason),
            attempts=max(state.attempt, 1),
        )
        in_batch = layout.batch_of(state.position) in batches
        out.append(
            dataclasses.replace(
                state,
                state=State.DONE if in_batch else State.SKIPPED,
                result=record,
                durable=True,  # re-derivable: the cancellation itself is recorded
            )
        )
    return tuple(out)
