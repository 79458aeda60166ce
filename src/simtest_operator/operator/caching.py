"""The watch-fed cache the campaign loops read: views grouped by campaign.

kopf keeps one index per watched kind (``handlers.py`` declares them); each maps a key to the
views of the objects under it. This module only reads those mappings, so tests can hand in plain
dicts instead of kopf indexes.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable, Mapping
from typing import Any

from simtest_operator.operator.actions import Kind
from simtest_operator.operator.admission import WorkloadView
from simtest_operator.operator.jobviews import JobView
from simtest_operator.operator.observed import (
    BatchView,
    CampaignView,
    EnvironmentView,
    NodeView,
    PodView,
)

CampaignKey = tuple[str, str]
"""(namespace, campaign name)."""
ALL_NODES = "*"
"""The one key of the node index."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Cache:
    """Read access to the indexes."""

    campaigns: Mapping[Any, Iterable[CampaignView]]
    batches: Mapping[Any, Iterable[BatchView]]
    environments: Mapping[Any, Iterable[EnvironmentView]]
    pods: Mapping[Any, Iterable[PodView]]
    nodes: Mapping[Any, Iterable[NodeView]] | None
    """None when the operator does not watch nodes."""
    jobs: Mapping[Any, Iterable[JobView]] = dataclasses.field(default_factory=dict)
    """helmfile Jobs by (namespace, campaign) (``provisioner: Helmfile``)."""
    workloads: Mapping[Any, Iterable[WorkloadView]] = dataclasses.field(default_factory=dict)
    """Kueue Workloads by (namespace, campaign) (``spec.execution.queueName``)."""

    def campaign(self, key: CampaignKey) -> CampaignView | None:
        """The campaign's view, if it exists."""
        return next(iter(self.campaigns.get(key, ())), None)

    def batches_of(self, key: CampaignKey) -> list[BatchView]:
        """The campaign's batches."""
        return list(self.batches.get(key, ()))

    def environments_of(self, key: CampaignKey) -> list[EnvironmentView]:
        """The campaign's environments."""
        return list(self.environments.get(key, ()))

    def pods_of(self, key: CampaignKey) -> dict[str, PodView]:
        """The campaign's simulator pods by name."""
        return {p.name: p for p in self.pods.get(key, ())}

    def jobs_of(self, key: CampaignKey) -> dict[str, JobView]:
        """The campaign's helmfile Jobs by name."""
        return {j.name: j for j in self.jobs.get(key, ())}

    def workload_of(self, key: CampaignKey) -> WorkloadView | None:
        """The campaign's Kueue Workload, if it has one."""
        return next(iter(self.workloads.get(key, ())), None)

    def node_map(self) -> dict[str, NodeView] | None:
        """All nodes by name (None when nodes are not watched)."""
        if self.nodes is None:
            return None
        return {n.name: n for n in self.nodes.get(ALL_NODES, ())}

    def lookup(self, key: CampaignKey, kind: Kind, name: str) -> tuple[bool, str, bool] | None:
        """(present, resourceVersion, deleting) of one object of the campaign, for expectations."""
        return self.lookups(key)(kind, name)

    def lookups(self, key: CampaignKey) -> Callable[[Kind, str], tuple[bool, str, bool] | None]:
        """:meth:`lookup` for many names at once: each kind's views are indexed by name on
        first use, so checking E expectations against N cached objects costs O(E + N), not
        O(E x N) (a loop checks its expectations on every wake-up; at 200 in flight that is
        hundreds of each). Use the returned function right away: it does not see later events.
        """
        sources: dict[Kind, Mapping[Any, Iterable[Any]]] = {
            Kind.BATCH: self.batches,
            Kind.ENVIRONMENT: self.environments,
            Kind.POD: self.pods,
            Kind.JOB: self.jobs,
            Kind.WORKLOAD: self.workloads,
        }
        indexed: dict[Kind, dict[str, Any]] = {}

        def lookup(kind: Kind, name: str) -> tuple[bool, str, bool] | None:
            found: Any
            if kind is Kind.CAMPAIGN:
                found = self.campaign(key)
            elif kind in sources:
                by_name = indexed.get(kind)
                if by_name is None:
                    by_name = indexed[kind] = {v.name: v for v in sources[kind].get(key, ())}
                found = by_name.get(name)
            else:
                return (True, "", False)
            if found is None:
                return None
            return (True, found.resource_version, bool(getattr(found, "deleting", False)))

        return lookup
