"""The evaluation step's part of a TestCampaign's status: ``status.evaluation`` and the condition
``Evaluated``.

The step adds evidence to a finished run, it does not re-run it: the campaign's phase stays what
the verdicts made it. ``Evaluated`` is Unknown (reason ``Running``) while the Job runs, True with
reason ``Passed`` or ``Failed`` once ``simtest evaluate`` answered (exit 0 or 1), False with reason
``Error`` when it could not (exit 2: bad input; a crash after the retries; the Job vanished).
"""

from __future__ import annotations

import dataclasses
import enum
from typing import Any

from simtest_operator.operator.status import conditions

CONDITION = "Evaluated"


class Stage(enum.StrEnum):
    """Where the evaluation step is; the condition's reason."""

    RUNNING = "Running"
    PASSED = "Passed"
    FAILED = "Failed"
    ERROR = "Error"

    @property
    def final(self) -> bool:
        """The step is over."""
        return self is not Stage.RUNNING


FINAL_REASONS = frozenset(s.value for s in Stage if s.final)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EvaluationState:
    """What the step's status should say."""

    job: str
    stage: Stage
    message: str
    evaluation_id: str = ""

    def condition(self) -> conditions.Desired:
        """The ``Evaluated`` condition."""
        status = None if self.stage is Stage.RUNNING else self.stage is not Stage.ERROR
        return conditions.Desired(
            type=CONDITION, status=status, reason=self.stage.value, message=self.message
        )

    def wire(self) -> dict[str, Any]:
        """``status.evaluation``."""
        out: dict[str, Any] = {"job": self.job}
        if self.evaluation_id:
            out["id"] = self.evaluation_id
        return out
