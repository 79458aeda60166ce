"""The watch-fed cache the campaign loops read: views grouped by campaign.

kopf keeps one index per watched kind (``handlers.py`` declares them); each maps a key to the
views of the objects under it. This module only reads those mappings, so tests can hand in plain
dicts instead of kopf indexes.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping
from typing import Any

from simtest_operator.operator.actions import Kind
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

    def node_map(self) -> dict[str, NodeView] | None:
        """All nodes by name (None when nodes are not watched)."""
        if self.nodes is None:
            return None
        return {n.name: n for n in self.nodes.get(ALL_NODES, ())}

    def lookup(self, key: CampaignKey, kind: Kind, name: str) -> tuple[bool, str, bool] | None:
        """(present, resourceVersion, deleting) of one object of the campaign, for expectations."""
        found: CampaignView | BatchView | EnvironmentView | PodView | JobView | None
        if kind is Kind.CAMPAIGN:
            found = self.campaign(key)
        elif kind is Kind.BATCH:
            found = next((b for b in self.batches.get(key, ()) if b.name == name), None)
        elif kind is Kind.ENVIRONMENT:
            found = next((e for e in self.environments.get(key, ()) if e.name == name), None)
        elif kind is Kind.POD:
            found = next((p for p in self.pods.get(key, ()) if p.name == name), None)
        elif kind is Kind.JOB:
            found = next((j for j in self.jobs.get(key, ()) if j.name == name), None)
        else:
            return (True, "", False)
        if found is None:
            return None
        deleting = bool(getattr(found, "deleting", False))
        return (True, found.resource_version, deleting)
