"""What a planning step reads: the watched views as given, and the frozen step built from them.

:class:`Inputs` is what the campaign loop hands over. :class:`Step` narrows it to one resolved
campaign (its spec, frozen list, layout, children) plus the configuration, once, so every phase
reads the same facts and none can change what a later one sees.
"""

from __future__ import annotations

import dataclasses
import datetime
from collections.abc import Callable, Mapping, Sequence
from collections.abc import Set as AbstractSet

from simtest_operator.api.v1alpha1 import TestCampaignSpec
from simtest_operator.operator import recording_results
from simtest_operator.operator.actions import Kind
from simtest_operator.operator.admission import WorkloadView
from simtest_operator.operator.batches import Layout
from simtest_operator.operator.jobviews import JobView
from simtest_operator.operator.observed import (
    BatchView,
    CampaignView,
    EnvironmentView,
    NodeView,
    PodView,
)
from simtest_operator.operator.scenariolists import StoredList
from simtest_operator.operator.status.counting import Tally
from simtest_operator.operator.status.searchstatus import SearchProgress
from simtest_operator.render import EnvironmentRequest, RenderedEnvironment
from simtest_operator.scenarios.pinned import PinnedScenario
from simtest_operator.settings import OperatorSettings

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
    seen_pods: AbstractSet[str] = frozenset()
    """Simulator pods the loop has watched exist or be deleted, named even when the cache no
    longer shows them: a seen pod that is gone was deleted, not hidden by a lagging watch."""
    nodes: Mapping[str, NodeView] | None = None
    """None when the operator cannot see nodes (then maxParallel defaults to batchSize)."""
    now: datetime.datetime
    last_status_write: datetime.datetime | None = None
    jobs: Mapping[str, JobView] = dataclasses.field(default_factory=dict)
    """helmfile Jobs by name (``provisioner: Helmfile``)."""
    workload: WorkloadView | None = None
    """The campaign's Kueue Workload (``spec.execution.queueName``), once it exists."""
    refused: Mapping[tuple[Kind, str], str] = dataclasses.field(default_factory=dict)
    """Creates the API server refused for good, by kind and name: its status code and message
    (the applier's :attr:`~simtest_operator.operator.applying.Applied.refused`, kept by the
    loop; the cache cannot show an object that was never created)."""
    search: SearchProgress | None = None
    """The campaign's searcher (``spec.search``), as the loop's
    :class:`~simtest_operator.operator.searching.CampaignSearch` reports it."""
    tally: Tally | None = None
    """The closed batches' counters as the campaign loop keeps them across steps (None: count
    them afresh; the same answer at a cost that grows with the campaign)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Step:
    """One step of a resolved campaign with a valid spec: what every phase reads."""

    inputs: Inputs
    spec: TestCampaignSpec
    config: OperatorSettings
    render: Renderer
    frozen: tuple[PinnedScenario, ...]
    """The frozen list's scenarios, in order."""
    layout: Layout
    batches: Mapping[int, BatchView]
    """This campaign's batches by index."""
    closed: Tally
    """Which of them are closed (every result in the status), and their counters."""
    envs: Sequence[EnvironmentView]
    """This campaign's environments."""
    run_key: str
    """The results run key pods record under; empty without a results database."""

    @property
    def campaign(self) -> CampaignView:
        """The campaign being planned."""
        return self.inputs.campaign

    @property
    def now(self) -> datetime.datetime:
        """The step's clock reading."""
        return self.inputs.now


def step(
    inputs: Inputs,
    stored: StoredList,
    spec: TestCampaignSpec,
    *,
    config: OperatorSettings,
    render: Renderer,
) -> Step:
    """The step of a campaign whose spec is valid and whose list is frozen."""
    campaign = inputs.campaign
    batches = {b.index: b for b in inputs.batches if b.campaign == campaign.name}
    if spec.search is None:
        frozen = stored.frozen.scenarios
        layout = stored.layout
    else:
        frozen, starts = waves(batches)
        layout = Layout(ids=tuple(s.id for s in frozen), batch_size=1, starts=starts)
    tally = inputs.tally if inputs.tally is not None else Tally()
    return Step(
        inputs=inputs,
        spec=spec,
        config=config,
        render=render,
        frozen=frozen,
        layout=layout,
        batches=batches,
        closed=tally.sync(batches, layout),
        envs=tuple(e for e in inputs.envs if e.campaign == campaign.name),
        run_key=recording_results.run_key(campaign) if spec.results.database_secret_ref else "",
    )


def waves(batches: Mapping[int, BatchView]) -> tuple[tuple[PinnedScenario, ...], tuple[int, ...]]:
    """A search's frozen list so far and where each wave starts: its batches' proposals, in
    batch order up to the first one not yet seen (each wave is one batch, created complete)."""
    frozen: list[PinnedScenario] = []
    starts: list[int] = []
    index = 0
    while index in batches and batches[index].proposals:
        starts.append(len(frozen))
        frozen.extend(batches[index].proposals)
        index += 1
    return tuple(frozen), tuple(starts)
