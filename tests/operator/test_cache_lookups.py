"""The cache's expectation lookups at scale.

Covers: ``Cache.lookups`` answers like ``Cache.lookup`` (present with resourceVersion, deleting,
absent, the campaign itself, kinds the cache does not hold); it reads each kind's views once per
call however many names are checked (O(expectations + objects), not their product); a fresh call
sees objects that appeared since.
"""

from __future__ import annotations

from collections.abc import Iterator

from simtest_operator.operator import observed
from simtest_operator.operator.actions import Kind
from simtest_operator.operator.caching import Cache

KEY = ("tests", "camp")


class CountingViews:
    """An index entry that counts how often it is iterated."""

    def __init__(self, views: list[observed.PodView]) -> None:
        self.views = views
        self.iterations = 0

    def __iter__(self) -> Iterator[observed.PodView]:
        self.iterations += 1
        return iter(self.views)


def pod(name: str, version: int, *, deleting: bool = False) -> observed.PodView:
    meta: dict[str, object] = {"name": name, "namespace": "tests", "resourceVersion": str(version)}
    if deleting:
        meta["deletionTimestamp"] = "2030-01-01T00:00:00Z"
    return observed.pod_view({"metadata": meta})


def campaign() -> observed.CampaignView:
    return observed.campaign_view(
        {"metadata": {"name": "camp", "namespace": "tests", "resourceVersion": "7"}}
    )


def test_lookups_answer_like_lookup() -> None:
    pods = [pod("p0", 10), pod("p1", 11, deleting=True)]
    cache = Cache(
        campaigns={KEY: [campaign()]},
        batches={},
        environments={},
        pods={KEY: pods},
        nodes=None,
    )
    lookup = cache.lookups(KEY)
    assert lookup(Kind.POD, "p0") == (True, "10", False) == cache.lookup(KEY, Kind.POD, "p0")
    assert lookup(Kind.POD, "p1") == (True, "11", True)
    assert lookup(Kind.POD, "gone") is None
    assert lookup(Kind.ENVIRONMENT, "p0") is None
    assert lookup(Kind.CAMPAIGN, "camp") == (True, "7", False)
    assert lookup(Kind.CONFIG_MAP, "any") == (True, "", False)  # not cached: never waited for


def test_each_kind_is_read_once_per_call() -> None:
    views = CountingViews([pod(f"p{i}", i) for i in range(500)])
    cache = Cache(campaigns={}, batches={}, environments={}, pods={KEY: views}, nodes=None)
    lookup = cache.lookups(KEY)
    found = [lookup(Kind.POD, f"p{i}") for i in range(0, 1000, 2)]
    assert views.iterations == 1
    assert sum(f is not None for f in found) == 250
    views.views.append(pod("late", 900))
    assert lookup(Kind.POD, "late") is None  # one call is one snapshot
    assert cache.lookups(KEY)(Kind.POD, "late") == (True, "900", False)
    assert views.iterations == 2
