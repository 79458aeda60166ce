"""``simtest.dev/v1alpha1``: the wire schema of the three custom resources.

Only this package knows the serialised shape; the rest of the code base works on domain values
produced by :mod:`simtest_operator.api.converting`.

Names load on first use (PEP 562 ``__getattr__``): the simulator pod validates three wire models
of its run spec and should not build the kinds, manifests and status models (about 0.1 s of
every runner's start-up) to get them.
"""

from typing import TYPE_CHECKING

from simtest_operator import lazyimports

if TYPE_CHECKING:
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
    from simtest_operator.api.v1alpha1.manifests import (
        Manifest,
        ManifestError,
        parse,
        parse_campaign,
    )
    from simtest_operator.api.v1alpha1.search import (
        SearchObjective,
        SearchParameter,
        SearchSpec,
        SearchStrategy,
    )
    from simtest_operator.api.v1alpha1.sources import ScenarioSelection, ScenarioSource
    from simtest_operator.api.v1alpha1.status import Counters, Phase, ScenarioResult

_MODULES = {
    "API_VERSION": "common",
    "GROUP": "common",
    "VERSION": "common",
    "Condition": "common",
    "DriverModel": "environment",
    "EnvironmentSpec": "environment",
    "Provisioner": "environment",
    "SimulatorSettings": "environment",
    "SutConfig": "environment",
    "Criteria": "evaluation",
    "CriteriaPatch": "evaluation",
    "EvaluationSpec": "evaluation",
    "ExecutionSpec": "execution",
    "Isolation": "execution",
    "Resources": "execution",
    "KINDS": "kinds",
    "SCENARIO_BATCH": "kinds",
    "SIM_ENVIRONMENT": "kinds",
    "TEST_CAMPAIGN": "kinds",
    "EnvironmentPhase": "kinds",
    "FrozenScenario": "kinds",
    "OfflineEvaluationStatus": "kinds",
    "ResourceKind": "kinds",
    "ScenarioBatchSpec": "kinds",
    "ScenarioBatchStatus": "kinds",
    "SimEnvironmentSpec": "kinds",
    "SimEnvironmentStatus": "kinds",
    "TestCampaignSpec": "kinds",
    "TestCampaignStatus": "kinds",
    "Timings": "kinds",
    "Manifest": "manifests",
    "ManifestError": "manifests",
    "parse": "manifests",
    "parse_campaign": "manifests",
    "SearchObjective": "search",
    "SearchParameter": "search",
    "SearchSpec": "search",
    "SearchStrategy": "search",
    "ScenarioSelection": "sources",
    "ScenarioSource": "sources",
    "Counters": "status",
    "Phase": "status",
    "ScenarioResult": "status",
}


__getattr__ = lazyimports.loader(__name__, _MODULES)


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
