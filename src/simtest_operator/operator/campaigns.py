"""The campaign planner: one reconcile step of a whole campaign tree, as a pure function.

Inputs are the campaign, its frozen list and the views of every child (batches, environments,
pods) plus the nodes and the clock; the output is a :class:`~actions.Plan`. One planner per
campaign decides everything, so the in-flight window is one number with one writer, and every
status has exactly one writer — no two reconcilers race on the same field.

A step acts on observed state only. Results become durable in this order, each step after the
previous one is visible: pod terminated -> SimEnvironment status records the verdicts -> pod
deleted and the verdicts folded into the ScenarioBatch status -> SimEnvironment deleted. A crash
between any two steps leaves enough behind for the next operator to continue from.
"""

from __future__ import annotations

import dataclasses
import datetime
from collections.abc import Callable, Mapping, Sequence

from simtest_operator.api.v1alpha1 import TestCampaignSpec
from simtest_operator.errors import RenderError
from simtest_operator.operator import (
    bodies,
    campaignstatus,
    cancelling,
    environments,
    environmentstatus,
    helmfileteardown,
    names,
    observed,
    provisioning,
    recording_results,
    requests,
    statuses,
)
from simtest_operator.operator.actions import (
    Action,
    Create,
    Delete,
    Emit,
    Kind,
    Observation,
    PatchStatus,
    Plan,
    Provision,
)
from simtest_operator.operator.batches import (
    Layout,
    ScenarioState,
    Selection,
    State,
    cluster_slots,
    scenario_states,
    select,
    unstored_by_environment,
)
from simtest_operator.operator.configuration import OperatorConfig
from simtest_operator.operator.environments import Assessment, Limits
from simtest_operator.operator.jobviews import JobView
from simtest_operator.operator.observed import (
    BatchView,
    CampaignView,
    EnvironmentView,
    NodeView,
    PodView,
)
from simtest_operator.operator.scenariolists import StoredList
from simtest_operator.render import EnvironmentRequest, RenderedEnvironment
from simtest_operator.render.inputs import STARTUP_ALLOWANCE_SECONDS

Renderer = Callable[[EnvironmentRequest], RenderedEnvironment]


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Inputs:
    """Everything one step looks at."""

    campaign: CampaignView
    stored: StoredList | None
    """The frozen list (None until resolution has written it)."""
    resolution_error: str | None = None
    batches: Sequence[BatchView] = ()
    envs: Sequence[EnvironmentView] = ()
    pods: Mapping[str, PodView] = dataclasses.field(default_factory=dict)
    nodes: Mapping[str, NodeView] | None = None
    """None when the operator cannot see nodes (then maxParallel defaults to batchSize)."""
    now: datetime.datetime
    last_status_write: datetime.datetime | None = None
    jobs: Mapping[str, JobView] = dataclasses.field(default_factory=dict)
    """helmfile Jobs by name (``provisioner: Helmfile``)."""


def plan(inputs: Inputs, *, config: OperatorConfig, render: Renderer) -> Plan:
    """One reconcile step."""
    campaign = inputs.campaign
    if campaign.deleting:
        return Plan(finished=True)
    if campaign.spec is None:
        return _halt(inputs, "Error", "InvalidSpec", campaign.spec_error or "invalid spec")
    if inputs.stored is None:
        if inputs.resolution_error is not None:
            return _halt(inputs, "Error", "ResolutionFailed", inputs.resolution_error)
        return _halt(inputs, "Resolving", "Resolving", "resolving scenario sources", final=False)
    return _Step(inputs, campaign.spec, config=config, render=render).run()


def _halt(inputs: Inputs, phase: str, reason: str, message: str, *, final: bool = True) -> Plan:
    actions = campaignstatus.halted(
        inputs.campaign, phase, reason, message, final=final, now=inputs.now
    )
    return Plan(actions=actions, finished=final)


class _Step:
    """The state of one planning step (a class only to share its many inputs)."""

    def __init__(
        self, inputs: Inputs, spec: TestCampaignSpec, *, config: OperatorConfig, render: Renderer
    ) -> None:
        assert inputs.stored is not None
        self.inputs = inputs
        self.spec = spec
        self.config = config
        self.render = render
        self.now = inputs.now
        self.campaign = inputs.campaign
        # the results run key pods record under; only campaigns with a database have one
        self.run_key = (
            recording_results.run_key(inputs.campaign) if spec.results.database_secret_ref else ""
        )
        self.frozen = inputs.stored.frozen.scenarios
        self.layout = Layout(
            ids=tuple(s.id for s in self.frozen), batch_size=inputs.stored.batch_size
        )
        self.batches = {b.index: b for b in inputs.batches if b.campaign == self.campaign.name}
        self.envs = [e for e in inputs.envs if e.campaign == self.campaign.name]
        self.actions: list[Action] = []
        self.wakes: list[datetime.datetime] = []
        self.start_latencies: list[float] = []
        self.overheads: list[float] = []

    def run(self) -> Plan:
        execution = self.spec.execution
        cancellation = cancelling.decide(self.spec, self.campaign.status, now=self.now)
        assessments = {env.name: self._assess(env) for env in self.envs}
        if cancellation is not None:
            assessments = {
                env.name: cancelling.assessment(
                    env, assessments[env.name], cancellation, now=self.now
                )
                for env in self.envs
            }
        states = scenario_states(
            self.layout,
            batches=self.batches.values(),
            envs=self.envs,
            assessments=assessments,
            retries=execution.retries,
        )
        if cancellation is not None:
            states = cancelling.states(
                states, self.layout, cancellation, batches=self.batches.keys()
            )
        for env in self.envs:
            self._environment(env, assessments[env.name])
        self.actions.extend(
            helmfileteardown.teardowns(
                self.spec,
                self.envs,
                jobs=self.inputs.jobs,
                pods=self.inputs.pods,
                batches=self.batches.values(),
                render=self.render,
                config=self.config,
            )
        )
        self._batches(states)
        folded = {s.id for s in states if s.state is State.FOLDED}
        for env in self.envs:
            self._cleanup(env, assessments[env.name], folded)
        complete = all(s.state.settled for s in states)
        in_flight = sum(
            1 for env in self.envs if not env.deleting and not assessments[env.name].ended
        )
        window = self._window()
        if not complete and not self.campaign.deleting and cancellation is None:
            self._start(states, in_flight=in_flight, window=window)
            limit = cancelling.deadline(self.spec, self.campaign.status)
            if limit is not None:
                self.wakes.append(limit)
        update = campaignstatus.progressed(
            self.campaign,
            self.spec,
            statuses.counters(states),
            batches=len(self.batches),
            complete=complete,
            cancellation=cancellation,
            now=self.now,
            last_write=self.inputs.last_status_write,
            status_interval=self.config.status_interval,
        )
        self.actions.extend(update.actions)
        if update.due is not None:
            self.wakes.append(update.due)
        counts = statuses.counters(states)
        return Plan(
            actions=tuple(self.actions),
            wake_at=min(self.wakes) if self.wakes else None,
            observation=Observation(
                in_flight=in_flight,
                queued=counts["queued"],
                window=window,
                start_latencies=tuple(self.start_latencies),
                overheads=tuple(self.overheads),
            ),
            finished=complete and not self.envs,
        )

    # --- environments ----------------------------------------------------------------------

    def _limits(self, env: EnvironmentView) -> Limits:
        execution = self.spec.execution
        return Limits(
            timeout_seconds=execution.timeout_seconds,
            pending_seconds=execution.pending_timeout_seconds,
            deadline_seconds=execution.timeout_seconds * len(env.scenarios)
            + STARTUP_ALLOWANCE_SECONDS,
            backstop_grace=self.config.backstop_grace,
            missing_grace=self.config.missing_pod_grace,
            node_not_ready_grace=self.config.node_not_ready_grace,
        )

    def _assess(self, env: EnvironmentView) -> Assessment:
        pod = self.inputs.pods.get(env.pod or env.name)
        return provisioning.assess(
            env,
            pod,
            jobs=self.inputs.jobs,
            pods=self.inputs.pods,
            nodes=self.inputs.nodes,
            now=self.now,
            limits=self._limits(env),
        )

    def _environment(self, env: EnvironmentView, assessment: Assessment) -> None:
        if env.deleting:
            return
        if assessment.wake_at is not None:
            self.wakes.append(assessment.wake_at)
        if assessment.needs_pod:
            self._provision(env)
            return
        desired = environmentstatus.desired_status(env, assessment)
        patch = statuses.changed_fields(desired, env.status)
        if patch:
            self.actions.append(PatchStatus(kind=Kind.ENVIRONMENT, name=env.name, patch=patch))
            started = assessment.timings.started
            queued = assessment.timings.queued
            if started and queued and "started" not in (env.status.get("timings") or {}):
                self.start_latencies.append(max((started - queued).total_seconds(), 0.0))
        pod = self.inputs.pods.get(env.pod or env.name)
        if env.finished and pod is not None:
            gone = environments.node_gone(pod, self.inputs.nodes)
            if not pod.deleting or gone:  # a graceful delete on a dead node never completes
                self.actions.append(
                    Delete(
                        kind=Kind.POD, name=pod.name, uid=pod.uid, grace_seconds=0 if gone else None
                    )
                )

    def _provision(self, env: EnvironmentView) -> None:
        request = requests.environment_request(
            self.spec, env, config=self.config, run_key=self.run_key
        )
        try:
            rendered = self.render(request)
        except RenderError as exc:
            status = environmentstatus.failed_status(
                env.scenario_ids,
                attempt=env.attempt,
                reason=f"cannot render the pod: {exc}",
                now=self.now,
            )
            self.actions.append(PatchStatus(kind=Kind.ENVIRONMENT, name=env.name, patch=status))
            return
        if provisioning.uses_helmfile(self.spec):
            self.actions.append(
                provisioning.provision(
                    self.spec,
                    env,
                    rendered,
                    config=self.config,
                    campaign_uid=self.campaign.uid,
                    now=self.now,
                )
            )
            return
        self.actions.append(
            Provision(
                environment=env.name,
                pod=rendered.pod,
                status=environmentstatus.provisioned_status(
                    env, pod=env.name, rendered_hash=rendered.content_hash, now=self.now
                ),
                scenario_ids=env.scenario_ids,
                attempt=env.attempt,
            )
        )

    def _cleanup(self, env: EnvironmentView, assessment: Assessment, folded: set[str]) -> None:
        if env.deleting or not env.finished or self.config.keep_finished_environments:
            return
        if all(scenario_id in folded for scenario_id in env.scenario_ids) and (
            helmfileteardown.torn_down(env, self.inputs.jobs)
        ):
            self.actions.append(Delete(kind=Kind.ENVIRONMENT, name=env.name, uid=env.uid))
            timings = assessment.timings
            if timings.queued and timings.finished:
                wall = (timings.finished - timings.queued).total_seconds()
                ran = sum(r.duration_seconds for r in assessment.results or ())
                self.overheads.append(max(wall - ran, 0.0) / max(len(env.scenarios), 1))

    # --- batches ---------------------------------------------------------------------------

    def _batches(self, states: Sequence[ScenarioState]) -> None:
        busy = {env.batch for env in self.envs}
        for index, batch in sorted(self.batches.items()):
            positions = self.layout.positions(index)
            if batch.name not in busy and len(batch.results) == len(positions):
                continue  # every result recorded and nothing running: the status is final
            mine = [states[p] for p in positions]
            desired = statuses.batch_status(states=mine, current=batch.status, now=self.now)
            patch = statuses.changed_fields(desired, batch.status)
            if not patch:
                continue
            known = {r.id for r in batch.results}
            folding = [
                s
                for s in mine
                if s.result is not None
                and s.id not in known
                and (s.state is State.FOLDED or (s.state is State.DONE and s.durable))
            ]
            new = tuple(s.result for s in folding if s.result is not None)
            for env_name, ids in unstored_by_environment(folding, self.envs):
                self.actions.append(
                    Emit(
                        kind=Kind.BATCH,
                        name=batch.name,
                        uid=batch.uid,
                        reason="ResultsNotStored",
                        message=f"{env_name or 'a finished environment'}: the results database "
                        f"did not take {', '.join(ids)} (verdicts kept in status; see the pod "
                        "log)",
                        warning=True,
                        terminal=True,  # once per environment: not rate limited
                    )
                )
            self.actions.append(
                PatchStatus(
                    kind=Kind.BATCH,
                    name=batch.name,
                    patch=patch,
                    resource_version=batch.resource_version if "results" in patch else None,
                    folded=new,
                )
            )
            if batch.status.get("phase") != desired["phase"] and desired["phase"] in (
                "Succeeded",
                "Failed",
                "Error",
            ):
                self.actions.append(
                    Emit(
                        kind=Kind.BATCH,
                        name=batch.name,
                        uid=batch.uid,
                        reason=f"Batch{desired['phase']}",
                        message=f"batch {index}: {desired['progress']} finished, "
                        f"{desired['passed']} passed, {desired['failed']} failed, "
                        f"{desired['errored']} errored",
                        warning=desired["phase"] == "Error",
                    )
                )

    # --- starting work ---------------------------------------------------------------------

    def _window(self) -> int:
        execution = self.spec.execution
        if execution.max_parallel is not None:
            return execution.max_parallel
        capacity = cluster_slots(
            self.inputs.nodes,
            per_node=execution.max_simulators_per_node,
            node_selector=execution.node_selector,
            tolerated=requests.tolerations(self.spec),
        )
        if capacity.slots <= 0:
            return execution.batch_size
        # A few pods beyond the slots wait in Pending, so the scheduler binds the next one the
        # moment a slot frees -- the operator is off the refill path. The scheduler still caps
        # what runs at the slots. Only when a Pending wait of a scenario's length cannot trip
        # pendingTimeoutSeconds.
        prefetch = 0
        if execution.pending_timeout_seconds >= 2 * execution.timeout_seconds:
            prefetch = self.config.prefetch_per_node * capacity.nodes
        return capacity.slots + prefetch

    def _start(self, states: Sequence[ScenarioState], *, in_flight: int, window: int) -> None:
        execution = self.spec.execution
        reuse = execution.isolation.value == "Reuse"
        units = select(
            states,
            self.layout,
            Selection(
                free_slots=window - in_flight,
                barrier=execution.batch_barrier,
                barrier_limit=execution.max_parallel,
                in_flight=in_flight,
                chunk=self.config.reuse_queue if reuse else 1,
                suspended=self.spec.suspend,
            ),
        )
        if len(units) > self.config.max_starts_per_step:
            units = units[: self.config.max_starts_per_step]
            self.wakes.append(self.now)  # the rest in the next step, once these are applied
        wanted_batches = {u.batch_index for u in units}
        if not execution.batch_barrier and not self.spec.suspend:
            wanted_batches |= self._lookahead(states)
        for index in sorted(wanted_batches - set(self.batches)):
            positions = self.layout.positions(index)
            self.actions.append(
                Create(
                    kind=Kind.BATCH,
                    body=bodies.batch(
                        campaign=self.campaign.name,
                        namespace=self.campaign.namespace,
                        campaign_uid=self.campaign.uid,
                        index=index,
                        scenarios=[self.frozen[p] for p in positions],
                    ),
                )
            )
        for unit in units:
            batch = self.batches.get(unit.batch_index)
            if batch is None:
                continue  # created above; its environments start once it is visible
            body = bodies.environment(
                campaign=self.campaign.name,
                namespace=self.campaign.namespace,
                batch_name=batch.name,
                batch_uid=batch.uid,
                name=names.environment(
                    self.campaign.name, unit.batch_index, unit.first, unit.attempt
                ),
                attempt=unit.attempt,
                isolation=execution.isolation.value,
                scenarios=[self.frozen[p] for p in unit.positions],
            )
            request = requests.environment_request(
                self.spec,
                observed.environment_view(body),
                config=self.config,
                run_key=self.run_key,
            )
            direct = not provisioning.uses_helmfile(self.spec)
            self.actions.append(
                Create(kind=Kind.ENVIRONMENT, body=body, provision=request if direct else None)
            )

    def _lookahead(self, states: Sequence[ScenarioState]) -> set[int]:
        """Create the next batch object once every scenario of the newest one has started, so
        the window never waits for a batch to appear."""
        if not self.batches:
            return {0} if self.layout.ids else set()
        newest = max(self.batches)
        following = newest + 1
        if following >= self.layout.batch_count():
            return set()
        started = all(states[p].state is not State.PENDING for p in self.layout.positions(newest))
        return {following} if started else set()
