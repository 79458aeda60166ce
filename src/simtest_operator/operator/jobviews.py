"""Views of helmfile Jobs (``provisioner: Helmfile``): the few facts the planner needs.

Like :mod:`observed`, parsing is pure and total, so one odd Job cannot stop a campaign. The
operator selects its Jobs by the campaign label; ``packaging.helmfilejobs`` adds the environment
and action labels read here.
"""

from __future__ import annotations

import dataclasses
import datetime
from collections.abc import Mapping

from simtest_operator.operator import names, observed
from simtest_operator.operator.observed import PodView, Raw
from simtest_operator.operator.status import reading

LABEL_JOB_ENVIRONMENT = "simtest.dev/environment"
"""Label of a helmfile Job naming its SimEnvironment (``packaging.helmfilejobs``)."""
LABEL_JOB_ACTION = "simtest.dev/helmfile-action"
"""Label of a helmfile Job: ``sync`` or ``destroy``."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class JobView:
    """A helmfile Job (``provisioner: Helmfile``)."""

    name: str
    namespace: str
    uid: str
    resource_version: str
    campaign: str
    environment: str
    batch: str
    action: str
    """``sync`` or ``destroy``."""
    created: datetime.datetime | None
    deleting: bool
    succeeded: bool
    """Condition ``Complete`` is True."""
    failed: bool
    """Condition ``Failed`` is True."""
    reason: str
    """Reason and message of the ``Failed`` condition (BackoffLimitExceeded, DeadlineExceeded)."""
    finished_at: datetime.datetime | None
    """When ``Complete`` or ``Failed`` became True."""

    @property
    def done(self) -> bool:
        """The Job ended, one way or the other."""
        return self.succeeded or self.failed


def last_run(job: JobView, pods: Mapping[str, PodView]) -> PodView | None:
    """The Job's pod that terminated last (its exit code and termination message tell how the
    Job's last try ended), if the cache still has one."""
    ran = [p for p in pods.values() if p.job == job.name and p.container.state == "terminated"]
    earliest = datetime.datetime.min.replace(tzinfo=datetime.UTC)
    return max(ran, key=lambda p: p.container.finished_at or p.created or earliest, default=None)


def _mapping(value: object) -> Raw:
    return value if isinstance(value, Mapping) else {}


def job_view(body: Raw) -> JobView:
    """Parse a Job body."""
    meta = _mapping(body.get("metadata"))
    status = _mapping(body.get("status"))
    labels = _mapping(meta.get("labels"))
    complete = observed.condition(status, "Complete")
    failed = observed.condition(status, "Failed")
    succeeded = complete is not None and complete.get("status") == "True"
    is_failed = failed is not None and failed.get("status") == "True"
    ended = complete if succeeded else failed if is_failed else None
    reason = ""
    if is_failed and failed is not None:
        reason = " ".join(str(p) for p in (failed.get("reason"), failed.get("message")) if p)
    return JobView(
        name=str(meta.get("name", "")),
        namespace=str(meta.get("namespace", "")),
        uid=str(meta.get("uid", "")),
        resource_version=str(meta.get("resourceVersion", "")),
        campaign=str(labels.get(names.LABEL_CAMPAIGN, "")),
        environment=str(labels.get(LABEL_JOB_ENVIRONMENT, "")),
        batch=str(labels.get(names.LABEL_BATCH, "")),
        action=str(labels.get(LABEL_JOB_ACTION, "")),
        created=reading.timestamp(meta.get("creationTimestamp")),
        deleting=meta.get("deletionTimestamp") is not None,
        succeeded=succeeded,
        failed=is_failed,
        reason=reason,
        finished_at=reading.timestamp((ended or {}).get("lastTransitionTime"))
        or reading.timestamp(status.get("completionTime")),
    )
