"""A search campaign on kwok fake nodes, end to end through the real control plane.

Covers: the operator proposes concrete scenarios of the logical scenario in waves (one
ScenarioBatch each) sized to the free slots and the next as results come back, until the budget
is spent; every proposal is a normal result with its proposal record in its batch; the status
says how far the search is (``status.search``); an operator restart in the middle replays the
searcher from the batches and the search goes on without a gap or a duplicate; the slots stay at
least 90 % busy while the search proposes (printed with a fixed list of the same runs for
comparison: ``pytest -s`` shows both).
"""

from __future__ import annotations

import shutil
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from tests.e2e import support

CUT_IN = support.REPO / "scenarios/library/cut-in/cut-in_highway_v25_gap15_dv10.xosc"
SLOTS = 9  # the dev cluster's 3 fake nodes x 3 simulator slots
BUDGET = 36
RESTARTED_AT = 20
"""Results told when the operator is restarted (its downtime is not the search's doing: the
busy share is measured before it)."""


def _campaign(name: str, *, search: bool) -> dict[str, Any]:
    body = support.campaign(name, template="kwok-search", execution={"maxSimulatorsPerNode": 3})
    body["spec"]["scenarios"]["include"] = ["cut-in.xosc"] if search else ["plain-*.xosc"]
    if search:
        body["spec"]["search"] = {
            "scenario": "cut-in.xosc",
            "parameters": [
                {"name": "EgoSpeed", "min": 15, "max": 35},
                {"name": "CutInGap", "min": 5, "max": 40},
            ],
            "strategy": "hybrid",  # the default: its model fits must not stall the waves
            "budget": BUDGET,
            "seed": 11,
        }
    return body


class Busy:
    """Samples of how many simulator pods run, while ``active`` says the work still comes."""

    def __init__(self, cluster: support.Cluster, active: Callable[[dict[str, Any]], bool]) -> None:
        self.cluster = cluster
        self.active = active
        self.samples: list[int] = []

    def __call__(self, name: str) -> None:
        status = self.cluster.status(name)
        if not self.active(status) or (not status.get("running") and not self.samples):
            return
        running = sum(
            1
            for p in self.cluster.pods()
            if p.status.phase == "Running" and not p.metadata.deletion_timestamp
        )
        self.samples.append(running)

    def share(self) -> float:
        return sum(self.samples) / (SLOTS * len(self.samples))


def test_a_search_keeps_the_slots_busy_and_survives_an_operator_restart(
    operator: support.OperatorProcess, cluster: support.Cluster, sources: Path
) -> None:
    support.scenario_files(sources / "scenarios", [f"plain-{i:03d}.xosc" for i in range(BUDGET)])
    shutil.copy(CUT_IN, sources / "scenarios" / "cut-in.xosc")
    shutil.copytree(Path(__file__).parent / "templates" / "kwok-search",
                    operator.templates / "kwok-search")  # fmt: skip
    searching = Busy(cluster, lambda s: (s.get("search") or {}).get("asked", 0) < BUDGET)
    listed = Busy(cluster, lambda s: s.get("queued", 1) > 0)
    with support.running(operator):
        cluster.create(_campaign("search", search=True))
        deadline = time.monotonic() + 60
        while (cluster.status("search").get("search") or {}).get("told", 0) < RESTARTED_AT:
            assert time.monotonic() < deadline, cluster.status("search")
            searching("search")
            time.sleep(0.1)
    busy = searching.share()
    with support.running(operator):  # a new operator process: the searcher is replayed
        status = cluster.wait_complete(
            "search", timeout=150, alive=operator.alive, during=lambda: searching("search")
        )
        cluster.create(_campaign("plain", search=False))
        cluster.wait_complete("plain", timeout=150, alive=operator.alive,
                              during=lambda: listed("plain"))  # fmt: skip
    search = status["search"]
    assert (search["asked"], search["told"], search["budget"]) == (BUDGET, BUDGET, BUDGET)
    assert status["total"] == BUDGET and search["failures"] == status["failed"]
    assert status["failed"] + status["passed"] == BUDGET
    results = cluster.results("search")
    assert sorted(results) == sorted(f"cut-in.xosc#search-{i}" for i in range(BUDGET))
    batches = sorted(
        (b for b in cluster.items("scenariobatches") if b["spec"]["campaign"] == "search"),
        key=lambda b: b["spec"]["index"],
    )
    proposals = [e["proposal"] for b in batches for e in b["spec"]["scenarios"]]
    assert [p["index"] for p in proposals] == list(range(BUDGET))
    assert len(batches[0]["spec"]["scenarios"]) >= SLOTS  # the first wave fills every slot
    assert len(batches) > BUDGET // SLOTS + 1  # later waves follow the results
    assert proposals[-1]["basis"] > 0
    fixed = listed.share()
    print(
        f"\nslots busy: search {busy:.0%} ({len(searching.samples)} samples, up to the restart), "
        f"the same runs as a fixed list {fixed:.0%} ({len(listed.samples)} samples)"
    )
    assert busy >= 0.9, f"search {busy:.0%} (a fixed list of the same runs: {fixed:.0%})"
