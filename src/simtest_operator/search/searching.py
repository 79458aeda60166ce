"""The searcher: asks a strategy for proposals within the budget and tells it the outcomes.

The operator and ``simtest run`` drive it the same way: ``ask`` as many proposals as there are
free slots, run them, ``tell`` each outcome when it arrives (any order), ask again. They persist
every proposal (index, values, basis) and the order of the tells; :meth:`Searcher.replay`
rebuilds the searcher from those after a restart and checks it proposes the same again.
"""

from __future__ import annotations

from collections.abc import Sequence

from simtest_operator.api.v1alpha1.search import SearchSpec
from simtest_operator.errors import SimtestError
from simtest_operator.search import strategies
from simtest_operator.search.records import Outcome, Proposal
from simtest_operator.search.spaces import SearchSpace


class ReplayError(SimtestError):
    """Replayed proposals differ from the recorded ones: the record belongs to another search."""


class Searcher:
    """Proposes concrete scenarios of one logical scenario, never beyond the budget."""

    def __init__(self, spec: SearchSpec, space: SearchSpace) -> None:
        self._spec = spec
        self._space = space
        self._strategy = strategies.create(spec, space)
        capacity = self._strategy.capacity
        self._limit = spec.budget if capacity is None else min(spec.budget, capacity)
        self._proposals: list[Proposal] = []
        self._points: list[strategies.Point] = []
        self._told: list[tuple[int, Outcome]] = []
        self._outcomes: dict[int, Outcome] = {}

    @property
    def spec(self) -> SearchSpec:
        """The search this searcher runs."""
        return self._spec

    @property
    def space(self) -> SearchSpace:
        """The dimensions it proposes values for."""
        return self._space

    @property
    def asked(self) -> int:
        """Proposals handed out so far."""
        return len(self._proposals)

    @property
    def told(self) -> int:
        """Outcomes received so far."""
        return len(self._told)

    @property
    def remaining(self) -> int:
        """Proposals the budget still allows (a grid ends early at the largest grid that fits
        the budget)."""
        return self._limit - self.asked

    @property
    def proposals(self) -> tuple[Proposal, ...]:
        """Every proposal, in the order asked."""
        return tuple(self._proposals)

    @property
    def records(self) -> list[tuple[Proposal, Outcome]]:
        """Told proposals with their outcomes, in tell order."""
        return [(self._proposals[i], outcome) for i, outcome in self._told]

    def ask(self, n: int) -> list[Proposal]:
        """Up to ``n`` new proposals (fewer when the budget runs out)."""
        batch = []
        for _ in range(max(min(n, self.remaining), 0)):
            index = self.asked
            history = strategies.History(
                index=index,
                told=[(self._points[i], outcome) for i, outcome in self._told],
                pending=[p for i, p in enumerate(self._points) if i not in self._outcomes],
            )
            values = self._space.decode(self._strategy.propose(history))
            proposal = Proposal(index=index, values=values, basis=self.told)
            self._proposals.append(proposal)
            # The strategy learns from where the run really was: the snapped, decoded values.
            self._points.append(tuple(self._space.encode(values)))
            batch.append(proposal)
        return batch

    def tell(self, index: int, outcome: Outcome) -> None:
        """Record the outcome of proposal ``index``; each proposal is told once."""
        if not 0 <= index < self.asked:
            raise ValueError(f"proposal {index} was never asked ({self.asked} asked)")
        if index in self._outcomes:
            raise ValueError(f"proposal {index} was already told")
        self._outcomes[index] = outcome
        self._told.append((index, outcome))

    @classmethod
    def replay(
        cls,
        spec: SearchSpec,
        space: SearchSpace,
        proposals: Sequence[Proposal],
        tells: Sequence[tuple[int, Outcome]],
    ) -> Searcher:
        """Rebuild a searcher from its recorded proposals and tells (in tell order).

        Each proposal is asked again once ``basis`` tells have been replayed; raises ReplayError
        when one comes out different (another spec, seed or space, or a non-deterministic
        strategy) or the record is inconsistent.
        """
        searcher = cls(spec, space)
        ordered = sorted(proposals, key=lambda p: p.index)
        if [p.index for p in ordered] != list(range(len(ordered))):
            raise ReplayError("recorded proposal indices are not 0, 1, 2, ...")
        pending_tells = list(tells)
        for recorded in ordered:
            if recorded.basis > len(tells):
                raise ReplayError(f"proposal {recorded.index} was based on unrecorded tells")
            while searcher.told < recorded.basis:
                index, outcome = pending_tells.pop(0)
                if index >= searcher.asked:
                    raise ReplayError(f"tell {index} precedes its proposal")
                searcher.tell(index, outcome)
            (again,) = searcher.ask(1)
            if again.basis != recorded.basis or not _same(again, recorded):
                raise ReplayError(
                    f"proposal {recorded.index} replays as {dict(again.values)}, "
                    f"recorded {dict(recorded.values)}"
                )
        for index, outcome in pending_tells:
            searcher.tell(index, outcome)
        return searcher


def _same(a: Proposal, b: Proposal) -> bool:
    if set(a.values) != set(b.values):
        return False
    for name, value in a.values.items():
        other = b.values[name]
        if isinstance(value, str) or isinstance(other, str):
            if str(value) != str(other):
                return False
        elif abs(float(value) - float(other)) > 1e-9 * max(1.0, abs(float(value))):
            return False
    return True
