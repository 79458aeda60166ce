"""Campaign loops: one asyncio task per campaign that plans and applies, woken by watch events.

Why not a kopf daemon: kopf gives every object with a daemon a finalizer, so deleting a campaign
would hang whenever the operator is down; DESIGN §3 wants finalizers only where something
outside the API must be cleaned up. The loop is the same idea without that cost: kopf's event
handlers wake it, and it never sleeps longer than the next time limit of its campaign.

One loop per campaign is the single writer of that campaign's statuses and the single decider of
its window, so nothing races. Each step waits until the cache shows the previous step's writes
(:mod:`expectations`), then plans from the cache and applies.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import datetime
import functools
import logging
import time
from collections.abc import Callable

from simtest_operator.errors import ClusterError, ScenarioError, SimtestError
from simtest_operator.operator import planning, recording_results, resolving, searching
from simtest_operator.operator.actions import Kind, Plan
from simtest_operator.operator.applying import Applier
from simtest_operator.operator.caching import Cache, CampaignKey
from simtest_operator.operator.client import Client
from simtest_operator.operator.expectations import Expectations
from simtest_operator.operator.metrics import Metrics
from simtest_operator.operator.observed import CampaignView
from simtest_operator.operator.scenariolists import StoredList
from simtest_operator.operator.status.counting import Tally
from simtest_operator.render import EnvironmentRequest, RenderedEnvironment
from simtest_operator.settings import OperatorSettings

log = logging.getLogger(__name__)

IDLE_SECONDS = 60.0
"""A loop plans at least this often even without events (a safety net for missed wake-ups)."""


def utcnow() -> datetime.datetime:
    """The wall clock (the only clock the loops read; the planner gets ``now`` passed in)."""
    return datetime.datetime.now(datetime.UTC)


@dataclasses.dataclass(slots=True)
class Shared:
    """What every loop of one operator uses."""

    client: Client
    cache: Cache
    config: OperatorSettings
    metrics: Metrics
    render: Callable[[EnvironmentRequest], RenderedEnvironment]
    clock: Callable[[], datetime.datetime] = utcnow


class CampaignLoop:
    """The control loop of one campaign."""

    def __init__(self, key: CampaignKey, shared: Shared) -> None:
        self.key = key
        self.shared = shared
        self.wake = asyncio.Event()
        self.expectations = Expectations()
        self.stored: StoredList | None = None
        self.tally = Tally()
        """The closed batches' counters, carried from step to step (a step then reads only the
        batches that changed)."""
        self.resolution_error: str | None = None
        self.resolution_generation = 0
        self.search: searching.CampaignSearch | None = None
        """The campaign's searcher (``spec.search``), replayed from its batches once resolved."""
        self.refused: dict[tuple[Kind, str], str] = {}
        """Creates the API server refused for good while this loop ran (the planner words them
        where they matter: the evaluation Job)."""
        self.seen_pods: set[str] = set()
        """Simulator pods the cache has shown or the watch reported deleted while this loop ran
        (a pod deleted before a status write recorded it is still known to have existed)."""
        self.last_status_write: datetime.datetime | None = None
        self.wake_at: datetime.datetime | None = None
        self.backoff = 1.0
        self.recorder = recording_results.CampaignRecorder(shared.client, clock=shared.clock)
        namespace, name = key
        self.applier = Applier(
            client=shared.client,
            namespace=namespace,
            campaign=name,
            campaign_uid=self._uid,
            metrics=shared.metrics,
            event_interval=shared.config.pacing.event_interval,
            parallel=shared.config.pacing.api_workers,
            render=shared.render,
        )

    def _uid(self) -> str:
        campaign = self.shared.cache.campaign(self.key)
        return campaign.uid if campaign else ""

    async def run(self) -> None:
        """Plan and apply until the campaign is deleted (then return)."""
        while True:
            await self._sleep()
            try:
                if not await self.step():
                    return
                self.backoff = 1.0
            except asyncio.CancelledError:
                raise
            except Exception:  # a loop must survive anything one step throws
                log.exception(
                    "%s/%s: reconcile step failed; retrying in %.0fs", *self.key, self.backoff
                )
                self.wake_at = self.shared.clock() + datetime.timedelta(seconds=self.backoff)
                self.backoff = min(self.backoff * 2, 60.0)

    async def _sleep(self) -> None:
        now = self.shared.clock()
        timeout = IDLE_SECONDS
        if self.wake_at is not None:
            timeout = min(max((self.wake_at - now).total_seconds(), 0.0), IDLE_SECONDS)
        if not self.wake.is_set() and timeout > 0:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self.wake.wait(), timeout)
        if self.shared.config.pacing.coalesce_seconds > 0:
            await asyncio.sleep(self.shared.config.pacing.coalesce_seconds)
        self.wake.clear()

    async def step(self) -> bool:
        """One reconcile step; False when the campaign is gone."""
        shared = self.shared
        cache = shared.cache
        now = shared.clock()
        if not self.expectations.satisfied(cache.lookups(self.key), now=now):
            self.wake_at = self.expectations.deadline
            return True
        campaign = cache.campaign(self.key)
        if campaign is None or campaign.deleting:
            return False
        started = time.perf_counter()
        if self.stored is None and campaign.spec is not None:
            await self._resolve(campaign)
            now = shared.clock()
        if self.search is None and self.stored is not None and campaign.spec is not None:
            await self._replay(campaign)
        planning_started = time.perf_counter()  # reading the cache and planning: no API calls
        if self.search is not None:
            self.search.learn(cache.batches_of(self.key))
        pods = cache.pods_of(self.key)
        self.seen_pods.update(pods)
        inputs = planning.Inputs(
            campaign=campaign,
            stored=self.stored,
            resolution_error=self.resolution_error,
            batches=cache.batches_of(self.key),
            envs=cache.environments_of(self.key),
            pods=pods,
            seen_pods=frozenset(self.seen_pods),
            nodes=cache.node_map(),
            now=now,
            last_status_write=self.last_status_write,
            jobs=cache.jobs_of(self.key),
            workload=cache.workload_of(self.key),
            refused=dict(self.refused),
            search=self.search.progress() if self.search is not None else None,
            tally=self.tally,
        )
        plan = planning.plan(inputs, config=shared.config, render=shared.render)
        shared.metrics.plan.observe(time.perf_counter() - planning_started)
        applied = await self.applier.apply(plan, now=now)
        self.refused.update(applied.refused)
        self.expectations.expect(applied.expectations, now=now)
        if applied.campaign_written:
            self.last_status_write = now
        self._observe(plan)
        self.wake_at = plan.wake_at
        if self.search is not None:
            wave = await self.search.advance(campaign, inputs.batches, plan.observation)
            if wave is not None:  # its batch shows up in the cache, and the next step starts it
                created = await self.applier.apply(Plan(actions=(wave,)), now=now)
                self.expectations.expect(created.expectations, now=now)
                applied.failures += created.failures
        searched = None
        if self.search is not None and recording_results.finish_of(campaign) is not None:
            searched = await self.search.record(inputs.batches)
        self.recorder.observe(campaign, self.stored, inputs.batches, search=searched)  # results DB
        shared.metrics.reconcile.observe(time.perf_counter() - started)
        if applied.failures or applied.conflict:
            retry = now + datetime.timedelta(seconds=self.backoff if applied.failures else 0.2)
            self.wake_at = min(self.wake_at, retry) if self.wake_at else retry
            self.backoff = min(self.backoff * 2, 30.0) if applied.failures else self.backoff
        return True

    def _observe(self, plan: Plan) -> None:
        namespace, name = self.key
        metrics = self.shared.metrics
        observation = plan.observation
        metrics.in_flight.labels(namespace=namespace, campaign=name).set(observation.in_flight)
        metrics.queued.labels(namespace=namespace, campaign=name).set(observation.queued)
        metrics.window.labels(namespace=namespace, campaign=name).set(observation.window)
        for seconds in observation.start_latencies:
            metrics.start_latency.observe(seconds)
        for seconds in observation.overheads:
            metrics.overhead.observe(seconds)

    async def _replay(self, campaign: CampaignView) -> None:
        """Rebuild the campaign's searcher from its waves (a new or restarted operator)."""
        spec = campaign.spec
        assert spec is not None and self.stored is not None
        if spec.search is None or not self.stored.frozen.scenarios:
            return
        base = self.stored.frozen.scenarios[0]
        try:
            space, target = await resolving.search_space(
                self.shared.client, campaign, base, config=self.shared.config
            )
        except (ScenarioError, OSError) as exc:
            raise ClusterError(f"cannot fetch the search's logical scenario: {exc}") from exc
        try:
            self.search = await searching.CampaignSearch.replayed(
                spec.search, space, target, self.shared.cache.batches_of(self.key)
            )
        except SimtestError as exc:  # the record does not replay: it never will
            self.stored = None
            self.resolution_error = f"the search cannot be replayed from its batches: {exc}"
            self.resolution_generation = campaign.generation

    async def _resolve(self, campaign: CampaignView) -> None:
        if self.resolution_error is not None and self.resolution_generation == campaign.generation:
            return
        self.resolution_error = None
        self.stored = await resolving.load(self.shared.client, campaign)
        if self.stored is not None:
            return
        # Say "Resolving" first: resolution may take a while (git clone, downloads).
        resolving_plan = planning.plan(
            planning.Inputs(campaign=campaign, stored=None, now=self.shared.clock()),
            config=self.shared.config,
            render=self.shared.render,
        )
        await self.applier.apply(resolving_plan, now=self.shared.clock())
        try:
            self.stored = await resolving.resolve(
                self.shared.client, campaign, config=self.shared.config, render=self.shared.render
            )
        except ScenarioError as exc:
            self.resolution_error = str(exc)
            self.resolution_generation = campaign.generation
        except (ClusterError, OSError) as exc:
            raise ClusterError(f"resolution failed transiently: {exc}") from exc
        except SimtestError as exc:
            self.resolution_error = str(exc)
            self.resolution_generation = campaign.generation


class Loops:
    """The campaign loops of one operator."""

    def __init__(self, shared: Shared) -> None:
        self.shared = shared
        self.loops: dict[CampaignKey, tuple[CampaignLoop, asyncio.Task[None]]] = {}

    def ensure(self, key: CampaignKey) -> None:
        """Start the campaign's loop if needed, and wake it."""
        entry = self.loops.get(key)
        if entry is None or entry[1].done():
            loop = CampaignLoop(key, self.shared)
            task = asyncio.get_running_loop().create_task(
                loop.run(), name=f"campaign {key[0]}/{key[1]}"
            )
            task.add_done_callback(functools.partial(self._finished, key))
            self.loops[key] = (loop, task)
            entry = self.loops[key]
        entry[0].wake.set()

    def wake(self, key: CampaignKey) -> None:
        """Wake a campaign's loop (no-op when it has none)."""
        entry = self.loops.get(key)
        if entry is not None:
            entry[0].wake.set()

    def pod_deleted(self, key: CampaignKey, pod: str) -> None:
        """The watch reported a campaign's simulator pod deleted: remember it, wake the loop."""
        entry = self.loops.get(key)
        if entry is not None:
            entry[0].seen_pods.add(pod)
            entry[0].wake.set()

    def wake_all(self) -> None:
        """Wake every loop (node changes affect every window)."""
        for loop, _ in self.loops.values():
            loop.wake.set()

    def stop(self, key: CampaignKey) -> None:
        """Stop a deleted campaign's loop."""
        entry = self.loops.pop(key, None)
        if entry is not None:
            entry[1].cancel()
        self.shared.metrics.forget(*key)

    def _finished(self, key: CampaignKey, _: object) -> None:
        entry = self.loops.get(key)
        if entry is not None and entry[1].done():
            self.loops.pop(key, None)
            self.shared.metrics.forget(*key)

    async def close(self) -> None:
        """Cancel every loop and wait for them."""
        tasks = [task for _, task in self.loops.values()]
        self.loops.clear()
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
