"""Reading watched statuses as the api's typed status models.

A status read here is a :class:`~simtest_operator.api.v1alpha1.TestCampaignStatus`,
:class:`~simtest_operator.api.v1alpha1.ScenarioBatchStatus` or
:class:`~simtest_operator.api.v1alpha1.SimEnvironmentStatus` -- the models the CRDs are generated
from -- built with ``model_construct`` after a lenient parse of each field, not validated. One odd
field (a hand-edited status, a newer operator's phase, a condition without a time) must not stop a
campaign, and validation rejects a status as a whole: here a value that does not parse reads as if
absent (the model's default, and not in ``model_fields_set``), as the views always read it.

Cost: the views are parsed on every watch event, for thousands of objects per campaign
(``bench/operator_scale.py``). A reading costs about 10 us (validation would be about 3 us, but
then needs this path as its fallback); batch and environment results are left out and read
once, into domain records.

Decisions read these models; merge patches are computed against the wire form the views keep
beside them (:mod:`.patches`), and fields the builders carry over (times, conditions) are copied
from it verbatim.
"""

from __future__ import annotations

import datetime
from collections.abc import Mapping
from typing import Any

from simtest_operator.api.v1alpha1 import (
    Condition,
    Counters,
    EnvironmentPhase,
    OfflineEvaluationStatus,
    Phase,
    Provisioner,
    ScenarioBatchStatus,
    SimEnvironmentStatus,
    TestCampaignStatus,
    Timings,
)
from simtest_operator.api.v1alpha1.common import ConditionStatus
from simtest_operator.api.v1alpha1.kinds import HelmfileJobs
from simtest_operator.verdicts import Verdict

Raw = Mapping[str, Any]

_UNKNOWN_TIME = datetime.datetime(1970, 1, 1, tzinfo=datetime.UTC)
"""The transition time of a condition whose own is missing or malformed (a required field)."""
_COUNTERS = tuple((name, str(field.alias)) for name, field in Counters.model_fields.items())


def timestamp(value: Any) -> datetime.datetime | None:
    """An RFC 3339 timestamp as an aware datetime; None when absent or malformed."""
    if not isinstance(value, str) or not value:
        return None
    try:
        parsed = datetime.datetime.fromisoformat(value.replace("Z", "+00:00"))
    except ValueError:
        return None
    return parsed if parsed.tzinfo else parsed.replace(tzinfo=datetime.UTC)


def campaign(wire: Raw) -> TestCampaignStatus:
    """A TestCampaign's status."""
    fields = _common(wire)
    if isinstance(scenario_list := wire.get("scenarioList"), str):
        fields["scenario_list"] = scenario_list
    if isinstance(batches := wire.get("batches"), int):
        fields["batches"] = int(batches)
    if isinstance(throughput := wire.get("throughput"), int | float):
        fields["throughput"] = float(throughput)
    evaluation = wire.get("evaluation")
    if isinstance(evaluation, Mapping) and isinstance(job := evaluation.get("job"), str):
        found = evaluation.get("id")
        fields["evaluation"] = OfflineEvaluationStatus.model_construct(
            job=job, id=found if isinstance(found, str) else None
        )
    return TestCampaignStatus.model_construct(_fields_set=set(fields), **_factories(fields))


def batch(wire: Raw) -> ScenarioBatchStatus:
    """A ScenarioBatch's status without its results: those are read once, into domain records
    (:attr:`~simtest_operator.operator.observed.BatchView.results`)."""
    fields = _common(wire)
    return ScenarioBatchStatus.model_construct(
        _fields_set=set(fields), **_factories(fields), results=[]
    )


def environment(wire: Raw) -> SimEnvironmentStatus:
    """A SimEnvironment's status without its results and conditions: the results are read once,
    into domain records (:attr:`~simtest_operator.operator.observed.EnvironmentView.results`),
    and of the conditions only the ``Provisioned`` time is needed (``provisioned_at``; the
    builders carry the conditions over from the wire). Parsing them would double the cost of an
    environment's view, which is read on every watch event. Empty strings read as absent, as the
    operator never writes them."""
    fields: dict[str, Any] = {}
    if (phase := _member(EnvironmentPhase, wire.get("phase"))) is not None:
        fields["phase"] = phase
    if isinstance(generation := wire.get("observedGeneration"), int):
        fields["observed_generation"] = int(generation)
    for name, alias in _ENVIRONMENT_TEXTS:
        if isinstance(text := wire.get(alias), str) and text:
            fields[name] = text
    if (verdict := _member(Verdict, wire.get("verdict"))) is not None:
        fields["verdict"] = verdict
    if (provisioner := _member(Provisioner, wire.get("provisioner"))) is not None:
        fields["provisioner"] = provisioner
    if isinstance(jobs := wire.get("jobs"), Mapping):
        sync, destroy = jobs.get("sync"), jobs.get("destroy")
        fields["jobs"] = HelmfileJobs.model_construct(
            sync=str(sync) if sync else None, destroy=str(destroy) if destroy else None
        )
    times = wire.get("timings")
    times = times if isinstance(times, Mapping) else {}
    moments = {k: t for k in _TIMINGS if (t := timestamp(times.get(k))) is not None}
    return SimEnvironmentStatus.model_construct(
        _fields_set={*fields, "timings"} if moments else set(fields),
        **fields,
        timings=Timings.model_construct(_fields_set=set(moments), **moments),
        results=[],
        conditions=[],
    )


_ENVIRONMENT_TEXTS = (
    ("scenario", "scenario"),
    ("reason", "reason"),
    ("node", "node"),
    ("pod", "pod"),
    ("rendered_hash", "renderedHash"),
)
_TIMINGS = tuple(Timings.model_fields)


def _member(kind: Any, value: Any) -> Any:
    """``value`` as a member of the string enum ``kind``; None when it is not one."""
    return kind(value) if isinstance(value, str) and value in kind.__members__.values() else None


def _factories(fields: dict[str, Any]) -> dict[str, Any]:
    """``fields`` plus those with a ``default_factory``: given explicitly (and left out of
    ``model_fields_set``), since ``model_construct`` inspects a factory's signature on every
    call (~50 us each)."""
    return {"conditions": [], **fields}


def _common(wire: Raw) -> dict[str, Any]:
    fields: dict[str, Any] = {}
    for name, alias in _COUNTERS:
        if isinstance(count := wire.get(alias), int):
            fields[name] = int(count)
    if (phase := _member(Phase, wire.get("phase"))) is not None:
        fields["phase"] = phase
    if isinstance(generation := wire.get("observedGeneration"), int):
        fields["observed_generation"] = int(generation)
    if isinstance(progress := wire.get("progress"), str):
        fields["progress"] = progress
    for name, alias in (("start_time", "startTime"), ("completion_time", "completionTime")):
        if (moment := timestamp(wire.get(alias))) is not None:
            fields[name] = moment
    if conditions := _conditions(wire):
        fields["conditions"] = conditions
    return fields


def _conditions(wire: Raw) -> list[Condition]:
    return [c for c in map(_condition, wire.get("conditions") or ()) if c is not None]


def _condition(wire: Any) -> Condition | None:
    if not isinstance(wire, Mapping):
        return None
    status = wire.get("status")
    fields: dict[str, Any] = {
        "type": str(wire.get("type", "")),
        "status": ConditionStatus(str(status))
        if status in ConditionStatus.__members__.values()
        else ConditionStatus.UNKNOWN,
        "reason": str(wire.get("reason", "")),
        "message": str(wire.get("message") or ""),
    }
    fields["last_transition_time"] = timestamp(wire.get("lastTransitionTime")) or _UNKNOWN_TIME
    if isinstance(generation := wire.get("observedGeneration"), int):
        fields["observed_generation"] = int(generation)
    return Condition.model_construct(**fields)


def counts(status: Counters) -> dict[str, int]:
    """The counters the status holds (absent ones left out), by wire name."""
    return {
        alias: getattr(status, name) for name, alias in _COUNTERS if name in status.model_fields_set
    }


def condition(status: TestCampaignStatus | ScenarioBatchStatus, kind: str) -> Condition | None:
    """The condition of type ``kind``, if any."""
    return next((c for c in status.conditions if c.type == kind), None)
