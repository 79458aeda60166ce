"""Admission through Kueue for one step: the window it allows, its Workload's create or delete.

The decisions are :func:`simtest_operator.operator.admission.gate`'s; this only feeds it the
step's facts.
"""

from __future__ import annotations

from simtest_operator.operator import admission
from simtest_operator.operator.actions import Kind
from simtest_operator.operator.planning.inputs import Step


def admit(step: Step, window: int, *, complete: bool, in_flight: int) -> admission.Gate:
    """What admission allows this step (the window unchanged without ``queueName``)."""
    campaign = step.campaign
    name = admission.workload_name(campaign.name)
    search = step.inputs.search
    # A search's list grows as it proposes: its Workload is sized by the budget, not by the
    # proposals so far (which are none when the Workload is created).
    scenarios = search.budget if search is not None else len(step.frozen)
    return admission.gate(
        step.spec,
        campaign=campaign.name,
        namespace=campaign.namespace,
        campaign_uid=campaign.uid,
        window=window,
        scenarios=scenarios,
        workload=step.inputs.workload,
        complete=complete,
        in_flight=in_flight,
        refused=step.inputs.refused.get((Kind.WORKLOAD, name)),
    )
