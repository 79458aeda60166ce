"""The TestCampaign's own status: phase, counters, conditions, and the event of a phase change.

Pure: from the campaign's current status and what the step found, the smallest status patch
(unchanged fields are left out, counter-only changes are coalesced to one write per
``statusInterval``) and at most one event. The planner
(:mod:`simtest_operator.operator.planning`) decides, this module words it.
"""

from __future__ import annotations

import dataclasses
import datetime
from collections.abc import Mapping, Sequence
from typing import Any

from simtest_operator.api.v1alpha1 import TestCampaignSpec
from simtest_operator.operator import cancelling, names
from simtest_operator.operator.actions import Action, Emit, Kind, PatchStatus
from simtest_operator.operator.observed import CampaignView
from simtest_operator.operator.status import conditions, counting, patches, reading
from simtest_operator.operator.status.evaluationstatus import EvaluationState
from simtest_operator.operator.status.searchstatus import SearchProgress


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Update:
    """What to write: status patch and event actions, and when to write a coalesced patch."""

    actions: tuple[Action, ...] = ()
    due: datetime.datetime | None = None
    """A counters-only patch was held back until then (``statusInterval``)."""


def halted(
    campaign: CampaignView,
    phase: str,
    reason: str,
    message: str,
    *,
    final: bool,
    now: datetime.datetime,
) -> tuple[Action, ...]:
    """Status of a campaign that cannot run (yet): invalid spec, resolving, resolution failed."""
    resolved = None if not final else False
    desired: dict[str, Any] = {
        "phase": phase,
        "observedGeneration": campaign.generation,
        "conditions": conditions.merge(
            campaign.status_wire.get("conditions"),
            [
                conditions.Desired(
                    type="Resolved", status=resolved, reason=reason, message=message
                ),
                conditions.Desired(type="Running", status=False, reason=reason, message=message),
                conditions.Desired(
                    type="Complete",
                    status=final,
                    reason=reason if final else "InProgress",
                    message=message,
                ),
                conditions.Desired(type="Degraded", status=final, reason=reason, message=message),
            ],
            now=now,
            generation=campaign.generation,
        ),
    }
    if final:
        desired["completionTime"] = campaign.status_wire.get(
            "completionTime"
        ) or conditions.rfc3339(now)
    patch = patches.changed_fields(desired, campaign.status_wire)
    return _written(
        campaign, patch, phase, reason=reason, message=message, warning=final, terminal=final
    )


def progressed(
    campaign: CampaignView,
    spec: TestCampaignSpec,
    counts: Mapping[str, int],
    *,
    batches: int,
    complete: bool,
    cancellation: cancelling.Cancellation | None,
    now: datetime.datetime,
    last_write: datetime.datetime | None,
    status_interval: float,
    evaluation: EvaluationState | None = None,
    admission: conditions.Desired | None = None,
    waiting: str | None = None,
    search: SearchProgress | None = None,
) -> Update:
    """Status of a resolved campaign from its scenario counters (and its evaluation step, when
    that has something to say, and its search's progress). ``admission`` is the ``Admitted``
    condition of a campaign with a Kueue queue; ``waiting`` its message while nothing is admitted
    and nothing runs (phase Pending, reason ``Queued``; no ``startTime`` yet)."""
    wire = campaign.status_wire
    total = counts["total"]
    if total == 0 and search is not None and search.open and cancellation is None:
        phase, reason, message = "Running", "Running", search.message()
    elif total == 0:
        phase, reason, message = "Error", "NoScenarios", "the selection matched no scenarios"
        complete = True
    elif cancellation is not None:
        phase = cancelling.CANCELLED_PHASE
        reason, message = cancellation.reason.value, cancellation.message
    elif complete:
        phase = counting.final_phase(counts)
        reason, message = phase, _summary(counts)
    elif spec.suspend:
        phase, reason, message = "Suspended", "Suspended", "spec.suspend is true"
    elif waiting is not None:
        phase, reason, message = "Pending", "Queued", waiting
    else:
        phase, reason, message = "Running", "Running", _summary(counts)
    start = wire.get("startTime") or conditions.rfc3339(now)
    finished = counting.finished_count(counts)
    desired: dict[str, Any] = {
        **counts,
        "phase": phase,
        "observedGeneration": campaign.generation,
        "progress": counting.progress(counts),
        "startTime": start,
        "scenarioList": names.scenario_list(campaign.name),
        "batches": batches,
    }
    if waiting is not None and not wire.get("startTime"):
        # Not started before admission: the wait in Kueue's queue does not count against
        # activeDeadlineSeconds (a Job's startTime waits for Kueue the same way).
        del desired["startTime"]
    started_at = reading.timestamp(start) or now
    minutes = (now - started_at).total_seconds() / 60.0
    if minutes > 0 and finished:
        desired["throughput"] = round(finished / minutes, 2)
    if complete:
        desired["completionTime"] = wire.get("completionTime") or conditions.rfc3339(now)
    if evaluation is not None:
        desired["evaluation"] = evaluation.wire()
    if search is not None:
        desired["search"] = search.wire()
    desired["conditions"] = _conditions(
        campaign, counts, phase=phase, reason=reason, message=message, complete=complete,
        cancelling_=cancellation is not None, now=now,
        extra=(
            *((evaluation.condition(),) if evaluation is not None else ()),
            *((admission,) if admission is not None else ()),
        ),
    )  # fmt: skip
    patch = patches.changed_fields(desired, wire)
    if not patch:
        return Update()
    if "conditions" in patch and _same_conditions(patch["conditions"], wire.get("conditions")):
        patch.pop("conditions")
    if patches.only_progress(patch) and last_write is not None:
        due = last_write + datetime.timedelta(seconds=status_interval)
        if now < due:
            return Update(due=due)
    return Update(
        actions=_written(
            campaign,
            patch,
            phase,
            reason=reason if cancellation is not None else phase,
            message=message,
            warning=phase == "Error" or reason == cancelling.Reason.DEADLINE_EXCEEDED,
            terminal=complete or cancellation is not None,
        )
    )


def _written(
    campaign: CampaignView,
    patch: Mapping[str, Any],
    phase: str,
    *,
    reason: str,
    message: str,
    warning: bool,
    terminal: bool,
) -> tuple[Action, ...]:
    """The status patch (when anything changed) and the event of a phase change."""
    actions: list[Action] = []
    if patch:
        actions.append(PatchStatus(kind=Kind.CAMPAIGN, name=campaign.name, patch=patch))
    if campaign.status.phase != phase:
        actions.append(
            event(campaign, reason=reason, message=message, warning=warning, terminal=terminal)
        )
    return tuple(actions)


def event(
    campaign: CampaignView, *, reason: str, message: str, warning: bool, terminal: bool
) -> Emit:
    """An event on the campaign: its phase changes here, the evaluation step's answers
    (:mod:`~simtest_operator.operator.planning.evaluating`)."""
    return Emit(
        kind=Kind.CAMPAIGN,
        name=campaign.name,
        uid=campaign.uid,
        reason=reason,
        message=message,
        warning=warning,
        terminal=terminal,
    )


def _conditions(
    campaign: CampaignView,
    counts: Mapping[str, int],
    *,
    phase: str,
    reason: str,
    message: str,
    complete: bool,
    cancelling_: bool,
    now: datetime.datetime,
    extra: Sequence[conditions.Desired] = (),
) -> list[dict[str, Any]]:
    total = counts["total"]
    degraded = counts["errored"] + counts["invalid"]
    return conditions.merge(
        campaign.status_wire.get("conditions"),
        [
            conditions.Desired(
                type="Resolved",
                status=True,
                reason="Frozen",
                message=f"{total} scenarios frozen in ConfigMap "
                f"{names.scenario_list(campaign.name)}",
            ),
            conditions.Desired(
                type="Running", status=phase == "Running", reason=reason, message=message
            ),
            conditions.Desired(
                type="Complete",
                status=complete,
                reason=reason if complete else "Cancelling" if cancelling_ else "InProgress",
                message=message,
            ),
            conditions.Desired(
                type="Degraded",
                status=degraded > 0 or total == 0,
                reason="ScenarioErrors" if degraded else reason if total == 0 else "AsExpected",
                message=f"{degraded} scenarios ended with Error or Invalid" if degraded else "",
            ),
            *extra,
        ],
        now=now,
        generation=campaign.generation,
    )


def _same_conditions(new: Sequence[Mapping[str, Any]], old: Any) -> bool:
    """Conditions equal except for message text of counters (avoid a write per scenario)."""
    if not isinstance(old, list) or len(old) != len(new):
        return False

    def key(c: Mapping[str, Any]) -> tuple[Any, ...]:
        return (c.get("type"), c.get("status"), c.get("reason"), c.get("observedGeneration"))

    return sorted(map(key, new)) == sorted(map(key, old))


def _summary(counts: Mapping[str, int]) -> str:
    return (
        f"{counting.progress(counts)} finished: {counts['passed']} passed, {counts['failed']} "
        f"failed, {counts['errored']} errored, {counts['timedOut']} timed out, "
        f"{counts['invalid']} invalid"
    )
