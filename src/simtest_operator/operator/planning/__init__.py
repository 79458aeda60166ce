"""The campaign planner: one reconcile step of a whole campaign tree, as a pure function.

Inputs are the campaign, its frozen list and the views of every child (batches, environments,
pods) plus the nodes and the clock; the output is a
:class:`~simtest_operator.operator.actions.Plan`. One planner per campaign decides everything,
so the in-flight window is one number with one writer, and every status has exactly one
writer -- no two reconcilers race on the same field.

A step is a fixed sequence of phases (:mod:`.steps`), each a function of the frozen
:class:`~.inputs.Step` returning its own actions and wake-ups: :mod:`.assessing` (what each
environment and scenario is doing), :mod:`.tending` (record it, provision missing pods, delete
finished ones), :mod:`.folding` (verdicts into batch statuses), :mod:`.cleaning` (teardown and
deletion of folded environments), :mod:`.starting` (the window and new work), :mod:`.evaluating`
(the evaluation step's Job once every verdict is in), then the campaign's own status. A rule
change means reading one phase.
"""

from simtest_operator.operator.planning.inputs import Inputs, Renderer
from simtest_operator.operator.planning.steps import plan

__all__ = ["Inputs", "Renderer", "plan"]
