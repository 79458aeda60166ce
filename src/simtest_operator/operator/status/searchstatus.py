"""A campaign's search progress (``status.search``): a few counters, whatever the budget.

The full record -- every proposal with its values and basis, every result -- lives in the
ScenarioBatches (one per wave) and the results store; the status only says how far the search is.
"""

from __future__ import annotations

import dataclasses
from typing import Any


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SearchProgress:
    """What the campaign's searcher has done so far."""

    strategy: str
    budget: int
    asked: int = 0
    told: int = 0
    failures: int = 0
    best: float | None = None
    best_scenario: str | None = None
    open: bool = True
    """The searcher may still propose (budget left and the strategy not exhausted): the
    campaign is not complete while it is, even when every proposal so far has its verdict."""

    def wire(self) -> dict[str, Any]:
        """``status.search`` (SearchStatus wire form)."""
        wire: dict[str, Any] = {
            "strategy": self.strategy,
            "budget": self.budget,
            "asked": self.asked,
            "told": self.told,
            "failures": self.failures,
        }
        if self.best is not None:
            wire["best"] = round(self.best, 6)
        if self.best_scenario is not None:
            wire["bestScenario"] = self.best_scenario
        return wire

    def message(self) -> str:
        """One line for the campaign's Running condition."""
        return (
            f"search: {self.asked}/{self.budget} proposed, {self.told} learnt from, "
            f"{self.failures} failure(s)"
        )
