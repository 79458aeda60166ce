"""The three custom resources: their specs, statuses and CRD naming.

TestCampaign (what to test and how) owns ScenarioBatches (slices of its frozen scenario list),
which own SimEnvironments (one provisioned environment per scenario, or one warm worker).
"""

from __future__ import annotations

import dataclasses
import datetime
import enum
from typing import Annotated, Any, ClassVar, Generic, Literal, TypeVar

from pydantic import Field, StringConstraints, model_validator

from simtest_operator.api.v1alpha1 import common
from simtest_operator.api.v1alpha1.common import ApiModel, DnsLabel
from simtest_operator.api.v1alpha1.environment import EnvironmentSpec, Provisioner
from simtest_operator.api.v1alpha1.evaluation import EvaluationSpec
from simtest_operator.api.v1alpha1.execution import ExecutionSpec, Isolation
from simtest_operator.api.v1alpha1.search import SearchSpec
from simtest_operator.api.v1alpha1.sources import ScenarioSelection
from simtest_operator.api.v1alpha1.status import CommonStatus, ScenarioResult
from simtest_operator.api.v1alpha1.storage import ArtifactsSpec, ResultsSpec
from simtest_operator.verdicts import Verdict

CAMPAIGN_NAME_MAX = 50
"""Campaign names stay short so child names (``<campaign>-b00042-e0001``) fit in 63 characters."""

Sha256 = Annotated[str, StringConstraints(pattern=r"^[0-9a-f]{64}$")]
ScenarioId = Annotated[str, StringConstraints(min_length=1, max_length=1024)]


# --- TestCampaign ------------------------------------------------------------------------------

_SEARCH_WITHOUT_BARRIER = (
    "spec.search proposes the next scenarios as results come back; spec.execution.batchBarrier "
    "would hold every wave until the previous one is done (leave it false)"
)
_OFFLINE_NEEDS_DATABASE = (
    "spec.evaluation.offline needs spec.results.databaseSecretRef (the evaluation step re-scores "
    "the run stored in the results database)"
)


class TestCampaignSpec(ApiModel):
    """What to test and how: scenarios, environment, execution, evaluation, storage."""

    __test__ = False  # not a pytest test class, despite the name

    cel_rules: ClassVar[tuple[dict[str, str], ...]] = (
        common.cel(
            "!has(self.evaluation) || !has(self.evaluation.offline) || "
            "(has(self.results) && has(self.results.databaseSecretRef))",
            _OFFLINE_NEEDS_DATABASE,
            field_path=".evaluation.offline",
        ),
        common.cel(
            "!has(self.search) || !has(self.execution) || !has(self.execution.batchBarrier) || "
            "!self.execution.batchBarrier",
            _SEARCH_WITHOUT_BARRIER,
            field_path=".search",
        ),
    )

    scenarios: ScenarioSelection
    """Scenario sources and selection; frozen (id + sha256) when the campaign starts. With
    ``search`` they name the sources the logical scenario file comes from."""
    search: SearchSpec | None = None
    """Search a logical scenario for failures instead of running the selection: the campaign
    runs the searcher's proposals (concrete scenarios of ``search.scenario``, which the selection
    must contain) and nothing else, proposing the next as results come back."""
    environment: EnvironmentSpec = Field(default_factory=EnvironmentSpec)
    """Environment template, values, system under test and simulator settings."""
    execution: ExecutionSpec = Field(default_factory=ExecutionSpec)
    """Batching, parallelism, limits, retries and placement."""
    evaluation: EvaluationSpec = Field(default_factory=EvaluationSpec)
    """Pass/fail criteria with per-scenario overrides."""
    artifacts: ArtifactsSpec = Field(default_factory=ArtifactsSpec)
    """Where recordings, logs and result files go."""
    results: ResultsSpec = Field(default_factory=ResultsSpec)
    """Results database."""
    suspend: bool = False
    """Pause, resumable: no new scenarios start while true (retries included); running ones
    finish. Setting it back to false continues where the campaign stopped."""
    cancel: bool = False
    """Stop now, for good: running simulator pods are deleted, their scenarios and every one not
    started yet end ``Skipped`` (reason ``cancelled``), phase ``Cancelled``, condition
    ``Complete=True`` with reason ``Cancelled``. Final: setting it back to false does nothing
    (use ``suspend`` to pause and resume)."""
    active_deadline_seconds: Annotated[int, Field(gt=0, le=31_536_000)] | None = None
    """Wall-clock limit of the whole campaign in seconds, counted from ``status.startTime`` (the
    first scenario start; suspended time counts too), like a Job's. When exceeded the campaign is
    cancelled as by ``cancel`` with reason ``DeadlineExceeded``. Unset: no limit."""

    @model_validator(mode="after")
    def _offline_needs_database(self) -> TestCampaignSpec:
        if self.evaluation.offline is not None and self.results.database_secret_ref is None:
            raise ValueError(_OFFLINE_NEEDS_DATABASE)
        return self

    @model_validator(mode="after")
    def _search_without_barrier(self) -> TestCampaignSpec:
        if self.search is not None and self.execution.batch_barrier:
            raise ValueError(_SEARCH_WITHOUT_BARRIER)
        return self


class OfflineEvaluationStatus(ApiModel):
    """The campaign's evaluation step (``spec.evaluation.offline``); its outcome is the condition
    ``Evaluated``."""

    job: DnsLabel
    """The evaluation Job (``<campaign>-evaluate``), created once."""
    id: Annotated[str, StringConstraints(max_length=253)] | None = None
    """The evaluation's id in the results database (``simtest compare --evaluation ID``)."""


class SearchStatus(ApiModel):
    """How far a campaign's search is: bounded, whatever the budget."""

    strategy: Annotated[str, StringConstraints(max_length=63)]
    budget: Annotated[int, Field(ge=0)]
    """Simulations the search may propose (``spec.search.budget``)."""
    asked: Annotated[int, Field(ge=0)] = 0
    """Concrete scenarios proposed so far (each in a ScenarioBatch)."""
    told: Annotated[int, Field(ge=0)] = 0
    """Results the searcher has learned from."""
    failures: Annotated[int, Field(ge=0)] = 0
    """Results with verdict Failed or Timeout."""
    best: float | None = None
    """Best value of the first objective so far (its metric, or the failures for ``verdict``)."""
    best_scenario: ScenarioId | None = None
    """The concrete scenario that reached ``best``."""


class TestCampaignStatus(CommonStatus):
    """Counters and conditions only: per-scenario results live in ScenarioBatch status, so the
    object stays far below etcd's size limit at 10,000 scenarios."""

    __test__ = False

    scenario_list: DnsLabel | None = None
    """ConfigMap holding the frozen scenario list (id, source, sha256)."""
    batches: Annotated[int, Field(ge=0)] = 0
    """ScenarioBatch objects created so far."""
    throughput: Annotated[float, Field(ge=0)] | None = None
    """Finished scenarios per minute since the start."""
    evaluation: OfflineEvaluationStatus | None = None
    """The evaluation step, once started (``spec.evaluation.offline``)."""
    search: SearchStatus | None = None
    """Progress of ``spec.search`` (counts only; every run is in the batches and the results
    store)."""


# --- ScenarioBatch -----------------------------------------------------------------------------


class SearchProposalRecord(ApiModel):
    """A search proposal as the frozen list keeps it."""

    index: Annotated[int, Field(ge=0)]
    """0, 1, 2, ... in the order asked."""
    basis: Annotated[int, Field(ge=0)]
    """Results the searcher had been told when it proposed this."""
    told: list[Annotated[int, Field(ge=0)]] = Field(default_factory=list)
    """Proposals whose results were told since the previous proposal, in the order told."""
    values: dict[str, str] = Field(default_factory=dict)
    """Parameter name -> value as text."""


class FrozenScenario(ApiModel):
    """One entry of the frozen scenario list."""

    id: ScenarioId
    """Stable scenario id (path inside its source, plus a distribution suffix where expanded)."""
    source: Annotated[str, StringConstraints(min_length=1, max_length=4096)]
    """Where the operator fetches the file from (URI of the resolved source + path)."""
    sha256: Sha256
    """Digest of the file content; a changed file is a different scenario."""
    overrides: dict[str, str] = Field(default_factory=dict)
    """OpenSCENARIO parameter values for this run (from the campaign and distributions)."""
    proposal: SearchProposalRecord | None = None
    """Set on a search's concrete scenario: what pins the search so it replays exactly."""


class ScenarioBatchSpec(ApiModel):
    """A contiguous slice of the campaign's frozen list."""

    campaign: DnsLabel
    """Owning TestCampaign."""
    index: Annotated[int, Field(ge=0)]
    """Position of the slice in the campaign (0-based)."""
    scenarios: Annotated[list[FrozenScenario], Field(min_length=1, max_length=1000)]
    """The slice."""


class ScenarioBatchStatus(CommonStatus):
    """Per-scenario results of the slice and its counters."""

    results: list[ScenarioResult] = Field(default_factory=list)
    """Final results, one per finished scenario."""


# --- SimEnvironment ----------------------------------------------------------------------------


class SimEnvironmentSpec(ApiModel):
    """One provisioned environment: a scenario (or, with Reuse, a queue of them) to run."""

    campaign: DnsLabel
    """Owning TestCampaign."""
    batch: DnsLabel
    """Owning ScenarioBatch."""
    scenarios: Annotated[list[FrozenScenario], Field(min_length=1, max_length=1000)]
    """What to run: one scenario with PerScenario isolation, several with Reuse."""
    isolation: Isolation = Isolation.PER_SCENARIO
    """Copied from the campaign so the environment is self-describing."""
    attempt: Annotated[int, Field(ge=1)] = 1
    """Attempt number (retries of infrastructure errors create a new environment)."""


class EnvironmentPhase(enum.StrEnum):
    """Lifecycle of one environment."""

    PENDING = "Pending"
    PROVISIONING = "Provisioning"
    SCHEDULED = "Scheduled"
    RUNNING = "Running"
    FINISHED = "Finished"
    TORN_DOWN = "TornDown"


class Timings(ApiModel):
    """When the environment passed each step; their differences are the orchestration overhead."""

    queued: datetime.datetime | None = None
    """Environment object created."""
    scheduled: datetime.datetime | None = None
    """Pod bound to a node."""
    started: datetime.datetime | None = None
    """Simulator container started."""
    finished: datetime.datetime | None = None
    """Simulator container terminated."""


class HelmfileJobs(ApiModel):
    """The Jobs that ran the environment's rendered helmfile (``provisioner: Helmfile``)."""

    sync: Annotated[str, StringConstraints(max_length=63)] | None = None
    """Job running ``helmfile sync`` (owned by the SimEnvironment)."""
    destroy: Annotated[str, StringConstraints(max_length=63)] | None = None
    """Job running ``helmfile destroy`` at teardown (owned by the ScenarioBatch, so it outlives
    the environment)."""


class SimEnvironmentStatus(ApiModel):
    """State, placement, timings and verdict of one environment."""

    phase: EnvironmentPhase = EnvironmentPhase.PENDING
    """Lifecycle phase."""
    observed_generation: Annotated[int, Field(ge=0)] | None = None
    """The ``metadata.generation`` the status reflects."""
    scenario: ScenarioId | None = None
    """Scenario running now (or last run)."""
    verdict: Verdict | None = None
    """Verdict of the (last) scenario."""
    reason: Annotated[str, StringConstraints(max_length=1024)] = ""
    """One-line reason for the verdict or the failure."""
    node: Annotated[str, StringConstraints(max_length=253)] | None = None
    """Node the simulator pod runs on."""
    pod: Annotated[str, StringConstraints(max_length=253)] | None = None
    """Simulator pod name."""
    rendered_hash: Sha256 | None = None
    """Digest of the rendered values and pod spec, for reproducibility."""
    provisioner: Provisioner | None = None
    """How the environment was provisioned: ``Pod`` (created directly) or ``Helmfile``."""
    jobs: HelmfileJobs | None = None
    """The helmfile Jobs of a ``Helmfile`` environment."""
    timings: Timings = Field(default_factory=Timings)
    """Queued, scheduled, started and finished times."""
    results: list[ScenarioResult] = Field(default_factory=list)
    """Results of the scenarios this environment ran."""
    conditions: list[common.Condition] = Field(default_factory=list)
    """Kubernetes-convention conditions."""


# --- CRD naming --------------------------------------------------------------------------------

SpecT = TypeVar("SpecT", bound=ApiModel)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class PrinterColumn:
    """One ``additionalPrinterColumns`` entry."""

    name: str
    type: Literal["string", "integer", "number", "boolean", "date"]
    json_path: str
    description: str = ""
    priority: int = 0


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ResourceKind(Generic[SpecT]):
    """Everything the CRD generator and the clients need to know about one kind."""

    kind: str
    plural: str
    singular: str
    short_names: tuple[str, ...]
    spec: type[SpecT]
    status: type[ApiModel]
    printer_columns: tuple[PrinterColumn, ...]
    description: str

    @property
    def crd_name(self) -> str:
        """``<plural>.<group>``."""
        return f"{self.plural}.{common.GROUP}"


def _counter_columns() -> tuple[PrinterColumn, ...]:
    return (
        PrinterColumn(name="Passed", type="integer", json_path=".status.passed"),
        PrinterColumn(name="Failed", type="integer", json_path=".status.failed"),
        PrinterColumn(name="Errored", type="integer", json_path=".status.errored"),
    )


_AGE = PrinterColumn(name="Age", type="date", json_path=".metadata.creationTimestamp")
_PHASE = PrinterColumn(name="Phase", type="string", json_path=".status.phase")
_PROGRESS = PrinterColumn(name="Progress", type="string", json_path=".status.progress")

TEST_CAMPAIGN: ResourceKind[TestCampaignSpec] = ResourceKind(
    kind="TestCampaign",
    plural="testcampaigns",
    singular="testcampaign",
    short_names=("tc", "campaign"),
    spec=TestCampaignSpec,
    status=TestCampaignStatus,
    printer_columns=(
        _PHASE,
        *_counter_columns(),
        _PROGRESS,
        PrinterColumn(
            name="Evaluated",
            type="string",
            json_path='.status.conditions[?(@.type=="Evaluated")].reason',
            description="Outcome of the evaluation step (spec.evaluation.offline)",
            priority=1,
        ),
        _AGE,
    ),
    description="A scenario-based test campaign: which OpenSCENARIO scenarios to run against which "
    "system under test, how, and with which pass/fail criteria.",
)
SCENARIO_BATCH: ResourceKind[ScenarioBatchSpec] = ResourceKind(
    kind="ScenarioBatch",
    plural="scenariobatches",
    singular="scenariobatch",
    short_names=("sb",),
    spec=ScenarioBatchSpec,
    status=ScenarioBatchStatus,
    printer_columns=(
        PrinterColumn(name="Campaign", type="string", json_path=".spec.campaign"),
        PrinterColumn(name="Index", type="integer", json_path=".spec.index"),
        _PHASE,
        _PROGRESS,
        _AGE,
    ),
    description="A slice of a TestCampaign's frozen scenario list with the per-scenario results.",
)
SIM_ENVIRONMENT: ResourceKind[SimEnvironmentSpec] = ResourceKind(
    kind="SimEnvironment",
    plural="simenvironments",
    singular="simenvironment",
    short_names=("senv", "simenv"),
    spec=SimEnvironmentSpec,
    status=SimEnvironmentStatus,
    printer_columns=(
        PrinterColumn(name="Scenario", type="string", json_path=".status.scenario"),
        _PHASE,
        PrinterColumn(name="Verdict", type="string", json_path=".status.verdict"),
        PrinterColumn(name="Node", type="string", json_path=".status.node"),
        _AGE,
    ),
    description="One provisioned simulation environment running one scenario (or a queue of "
    "scenarios on a warm simulator).",
)

KINDS: tuple[ResourceKind[Any], ...] = (TEST_CAMPAIGN, SCENARIO_BATCH, SIM_ENVIRONMENT)
