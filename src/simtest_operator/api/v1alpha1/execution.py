"""How a campaign runs: batching, parallelism, limits, retries, placement."""

from __future__ import annotations

import enum
from typing import Annotated, ClassVar

from pydantic import Field, model_validator

from simtest_operator.api.v1alpha1.common import ApiModel, DnsLabel, Quantity, Toleration, cel


class Isolation(enum.StrEnum):
    """Whether each scenario gets a fresh environment."""

    PER_SCENARIO = "PerScenario"
    """A fresh simulator pod per scenario (strongest isolation)."""
    REUSE = "Reuse"
    """A warm simulator runs several scenarios with a verified reset between them."""


class ResourceList(ApiModel):
    """Resources of one simulator pod."""

    cpu: Quantity = "1"
    """CPU, e.g. ``500m`` or ``2``."""
    memory: Quantity = "1Gi"
    """Memory, e.g. ``512Mi`` or ``4Gi``."""
    gpu: Annotated[int, Field(ge=0, le=16)] = 0
    """Number of ``nvidia.com/gpu`` devices."""


class Resources(ApiModel):
    """Requests and limits of each simulator pod (limits default to the requests)."""

    requests: ResourceList = Field(default_factory=ResourceList)
    """What the scheduler reserves for the pod."""
    limits: ResourceList | None = None
    """Upper bounds enforced at run time; unset means equal to the requests."""


class ExecutionSpec(ApiModel):
    """Execution parameters."""

    cel_rules: ClassVar[tuple[dict[str, str], ...]] = (
        cel(
            "!self.batchBarrier || !has(self.maxParallel) || self.maxParallel >= self.batchSize",
            "with batchBarrier, maxParallel must be at least batchSize "
            "(a barrier batch is submitted whole)",
            field_path=".maxParallel",
        ),
    )

    batch_size: Annotated[int, Field(ge=1, le=1000)] = 10
    """Scenarios per ScenarioBatch object (and per barrier step when batchBarrier is set)."""
    max_simulators_per_node: Annotated[int, Field(ge=1, le=64)] = 1
    """Simulators a node may run at once; nodes advertise this many ``simtest.dev/simulator``
    units and the Kubernetes scheduler enforces it."""
    max_parallel: Annotated[int, Field(ge=1, le=10000)] | None = None
    """Scenarios in flight at once; unset derives it from the cluster's simulator slots."""
    timeout_seconds: Annotated[int, Field(gt=0, le=86400)] = 60
    """Wall-clock limit of one scenario run; exceeded runs end as Timeout."""
    retries: Annotated[int, Field(ge=0, le=10)] = 2
    """Extra attempts for infrastructure errors (verdict Error) only; Failed is never retried."""
    pending_timeout_seconds: Annotated[int, Field(gt=0, le=86400)] = 600
    """A simulator pod still Pending after this long ends as Error (and may be retried)."""
    resources: Resources = Field(default_factory=Resources)
    """Requests and limits of each simulator pod."""
    node_selector: dict[str, str] = Field(default_factory=dict)
    """Node labels simulator pods must match."""
    tolerations: list[Toleration] = Field(default_factory=list)
    """Tolerations of simulator pods."""
    isolation: Isolation = Isolation.PER_SCENARIO
    """PerScenario (fresh pod per scenario) or Reuse (warm simulators)."""
    batch_barrier: bool = False
    """Run batch after batch, waiting for each to finish (the paper's behaviour, for comparison);
    the default keeps a window of maxParallel scenarios in flight and refills it immediately."""
    queue_name: DnsLabel | None = None
    """Kueue LocalQueue (in the campaign's namespace) that admits the campaign's simulators, as
    Kueue's ``kueue.x-k8s.io/queue-name`` label names it: the operator asks it for the window as
    one Workload and starts pods only within what it admits (docs/kueue.md). Unset: no Kueue."""

    @model_validator(mode="after")
    def _barrier_fits(self) -> ExecutionSpec:
        if (
            self.batch_barrier
            and self.max_parallel is not None
            and self.max_parallel < self.batch_size
        ):
            raise ValueError(
                "with batchBarrier, maxParallel must be at least batchSize "
                "(a barrier batch is submitted whole)"
            )
        return self
