"""Online evaluation: pure criteria over world snapshots, and the verdict they lead to.

Public API: :class:`Criteria` (defaults plus per-scenario overrides), :class:`OnlineEvaluator`
(fed one :class:`~simtest_operator.snapshots.WorldSnapshot` per step), :class:`ScenarioCriteria`
(a scenario's own CARLA ScenarioRunner criteria, judged by the evaluator), :func:`judge`
(evaluator plus :class:`RunFacts` -> :class:`Judgement`).
"""

from typing import TYPE_CHECKING

from simtest_operator import lazyimports

if TYPE_CHECKING:
    from simtest_operator.evaluation.carla_criteria import Outcome, ScenarioCriteria, Status
    from simtest_operator.evaluation.criteria import DEFAULT_TIME_LIMIT, Criteria
    from simtest_operator.evaluation.judging import Judgement, RunFacts, judge
    from simtest_operator.evaluation.online import (
        Collision,
        OffRoadCheck,
        OnlineEvaluator,
        Violation,
    )

# Loaded on first use: the offline modules (``simtest evaluate``) need none of these, and
# carla_criteria pulls in the OpenSCENARIO reader (about 150 ms at start-up).
_MODULES = {
    "Outcome": "carla_criteria",
    "ScenarioCriteria": "carla_criteria",
    "Status": "carla_criteria",
    "DEFAULT_TIME_LIMIT": "criteria",
    "Criteria": "criteria",
    "Judgement": "judging",
    "RunFacts": "judging",
    "judge": "judging",
    "Collision": "online",
    "OffRoadCheck": "online",
    "OnlineEvaluator": "online",
    "Violation": "online",
}


__getattr__ = lazyimports.loader(__name__, _MODULES)


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
