"""Online evaluation: pure criteria over world snapshots, and the verdict they lead to.

Public API: :class:`Criteria` (defaults plus per-scenario overrides), :class:`OnlineEvaluator`
(fed one :class:`~simtest_operator.snapshots.WorldSnapshot` per step), :class:`ScenarioCriteria`
(a scenario's own CARLA ScenarioRunner criteria, judged by the evaluator), :func:`judge`
(evaluator plus :class:`RunFacts` -> :class:`Judgement`).
"""

from simtest_operator.evaluation.carla_criteria import Outcome, ScenarioCriteria, Status
from simtest_operator.evaluation.criteria import DEFAULT_TIME_LIMIT, Criteria
from simtest_operator.evaluation.judging import Judgement, RunFacts, judge
from simtest_operator.evaluation.online import Collision, OffRoadCheck, OnlineEvaluator, Violation

__all__ = [
    "DEFAULT_TIME_LIMIT",
    "Collision",
    "Criteria",
    "Judgement",
    "OffRoadCheck",
    "OnlineEvaluator",
    "Outcome",
    "RunFacts",
    "ScenarioCriteria",
    "Status",
    "Violation",
    "judge",
]
