"""New work: how many environments may run at once, and which to create next.

The window is ``maxParallel`` or, without it, the simulator slots the scheduler can fill plus a
small prefetch. Within it :func:`~simtest_operator.operator.batches.select` picks retries first,
then unstarted scenarios; batch objects are created one ahead so the window never waits for one.
"""

from __future__ import annotations

import datetime

from simtest_operator.operator import bodies, names, observed, provisioning, requests
from simtest_operator.operator.actions import Action, Create, Kind
from simtest_operator.operator.batches import (
    Capacity,
    Progress,
    Selection,
    State,
    cluster_slots,
    select,
)
from simtest_operator.operator.planning.inputs import Step
from simtest_operator.operator.planning.outcomes import Outcome


def slots(step: Step) -> int:
    """How many simulators run at once: ``maxParallel``, else the slots the scheduler can fill,
    else (no node access) ``batchSize``."""
    execution = step.spec.execution
    if execution.max_parallel is not None:
        return execution.max_parallel
    capacity = _capacity(step)
    return capacity.slots if capacity.slots > 0 else execution.batch_size


def _capacity(step: Step) -> Capacity:
    execution = step.spec.execution
    return cluster_slots(
        step.inputs.nodes,
        per_node=execution.max_simulators_per_node,
        node_selector=execution.node_selector,
        tolerated=requests.tolerations(step.spec),
    )


def window(step: Step) -> int:
    """How many environments may be in flight."""
    execution = step.spec.execution
    if execution.max_parallel is not None:
        return execution.max_parallel
    capacity = _capacity(step)
    if capacity.slots <= 0:
        return execution.batch_size
    # A few pods beyond the slots wait in Pending, so the scheduler binds the next one the
    # moment a slot frees -- the operator is off the refill path. The scheduler still caps
    # what runs at the slots. Only when a Pending wait of a scenario's length cannot trip
    # pendingTimeoutSeconds.
    prefetch = 0
    if execution.pending_timeout_seconds >= 2 * execution.timeout_seconds:
        prefetch = step.config.pacing.prefetch_per_node * capacity.nodes
    return capacity.slots + prefetch


def start(step: Step, states: Progress, *, in_flight: int, window: int) -> Outcome:
    """Batch and environment objects to create (at most ``maxStartsPerStep`` environments;
    the rest in the next step, once these are applied)."""
    spec = step.spec
    execution = spec.execution
    reuse = execution.isolation.value == "Reuse"
    running = slots(step)
    units = select(
        states,
        step.layout,
        Selection(
            free_slots=window - in_flight,
            barrier=execution.batch_barrier,
            barrier_limit=execution.max_parallel,
            in_flight=in_flight,
            chunk=step.config.pacing.reuse_queue if reuse else 1,
            spread=running,
            suspended=spec.suspend,
        ),
    )
    wakes: tuple[datetime.datetime, ...] = ()
    limit = min(step.config.pacing.max_starts_per_step, _filling(running, in_flight, window))
    if len(units) > limit:
        units = units[:limit]
        wakes = (step.now,)
    wanted_batches = {u.batch_index for u in units}
    if not execution.batch_barrier and not spec.suspend:
        wanted_batches |= _lookahead(step, states)
    campaign = step.campaign
    actions: list[Action] = []
    for index in sorted(wanted_batches - set(step.batches)):
        actions.append(
            Create(
                kind=Kind.BATCH,
                body=bodies.batch(
                    campaign=campaign.name,
                    namespace=campaign.namespace,
                    campaign_uid=campaign.uid,
                    index=index,
                    scenarios=[step.frozen[p] for p in step.layout.positions(index)],
                ),
            )
        )
    direct = not provisioning.uses_helmfile(spec)
    for unit in units:
        batch = step.batches.get(unit.batch_index)
        if batch is None:
            continue  # created above; its environments start once it is visible
        body = bodies.environment(
            campaign=campaign.name,
            namespace=campaign.namespace,
            batch_name=batch.name,
            batch_uid=batch.uid,
            name=names.environment(campaign.name, unit.batch_index, unit.first, unit.attempt),
            attempt=unit.attempt,
            isolation=execution.isolation.value,
            scenarios=[step.frozen[p] for p in unit.positions],
        )
        request = requests.environment_request(
            spec, observed.environment_view(body), config=step.config, run_key=step.run_key
        )
        actions.append(
            Create(kind=Kind.ENVIRONMENT, body=body, provision=request if direct else None)
        )
    return Outcome(actions=tuple(actions), wakes=wakes)


def _filling(running: int, in_flight: int, window: int) -> int:
    """How many environments to create now: the prefetched ones (beyond the free slots) only in
    a later step than those that fill free slots.

    The applier creates a step's pods in parallel, so the scheduler meets them in any order and
    binds whichever come first; a prefetched pod must come after the pods the slots are meant
    for. With warm queues (largest first) the largest queue otherwise waited Pending behind
    smaller ones and ran last (the tail at s = 3 in ``bench/real_table1.py``)."""
    free = running - in_flight
    return free if 0 < free < window - in_flight else window


def _lookahead(step: Step, states: Progress) -> set[int]:
    """Create the next batch object once every scenario of the newest one has started, so
    the window never waits for a batch to appear."""
    if not step.batches:
        return {0} if step.layout.ids else set()
    newest = max(step.batches)
    following = newest + 1
    if following >= step.layout.batch_count():
        return set()
    started = all(states.state(p).state is not State.PENDING for p in step.layout.positions(newest))
    return {following} if started else set()
