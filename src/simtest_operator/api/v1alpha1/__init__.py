"""``simtest.dev/v1alpha1``: the wire schema of the three custom resources.

Only this package knows the serialised shape; the rest of the code base works on domain values
produced by :mod:`simtest_operator.api.converting`.
"""

from simtest_operator.api.v1alpha1.common import API_VERSION, GROUP, VERSION, Condition
from simtest_operator.api.v1alpha1.environment import (
    DriverModel,
    EnvironmentSpec,
    Provisioner,
    SimulatorSettings,
    SutConfig,
)
from simtest_operator.api.v1alpha1.evaluation import Criteria, CriteriaPatch, EvaluationSpec
from simtest_operator.api.v1alpha1.execution import ExecutionSpec, Isolation, Resources
from simtest_operator.api.v1alpha1.kinds import (
    KINDS,
    SCENARIO_BATCH,
    SIM_ENVIRONMENT,
    TEST_CAMPAIGN,
    EnvironmentPhase,
    FrozenScenario,
    OfflineEvaluationStatus,
    ResourceKind,
    ScenarioBatchSpec,
    ScenarioBatchStatus,
    SimEnvironmentSpec,
    SimEnvironmentStatus,
    TestCampaignSpec,
    TestCampaignStatus,
    Timings,
)
from simtest_operator.api.v1alpha1.manifests import Manifest, ManifestError, parse, parse_campaign
from simtest_operator.api.v1alpha1.search import (
    SearchObjective,
    SearchParameter,
    SearchSpec,
    SearchStrategy,
)
from simtest_operator.api.v1alpha1.sources import ScenarioSelection, ScenarioSource
from simtest_operator.api.v1alpha1.status import Counters, Phase, ScenarioResult

__all__ = [
    "API_VERSION",
    "GROUP",
    "KINDS",
    "SCENARIO_BATCH",
    "SIM_ENVIRONMENT",
    "TEST_CAMPAIGN",
    "VERSION",
    "Condition",
    "Counters",
    "Criteria",
    "CriteriaPatch",
    "DriverModel",
    "EnvironmentPhase",
    "EnvironmentSpec",
    "EvaluationSpec",
    "ExecutionSpec",
    "FrozenScenario",
    "Isolation",
    "Manifest",
    "ManifestError",
    "OfflineEvaluationStatus",
    "Phase",
    "Provisioner",
    "ResourceKind",
    "Resources",
    "ScenarioBatchSpec",
    "ScenarioBatchStatus",
    "ScenarioResult",
    "ScenarioSelection",
    "ScenarioSource",
    "SearchObjective",
    "SearchParameter",
    "SearchSpec",
    "SearchStrategy",
    "SimEnvironmentSpec",
    "SimEnvironmentStatus",
    "SimulatorSettings",
    "SutConfig",
    "TestCampaignSpec",
    "TestCampaignStatus",
    "Timings",
    "parse",
    "parse_campaign",
]
