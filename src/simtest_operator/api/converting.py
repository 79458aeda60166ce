"""Converters from the wire schema (pydantic, ``v1alpha1``) to the domain values the rest uses.

The versioned, serialised shape stays in ``api``; every converter here is the one place a wire
field turns into a domain field (kwok's ``internalversion/conversion.go``). A future ``v1beta1``
adds converters, not a copied domain.
"""

from __future__ import annotations

from simtest_operator.api import v1alpha1
from simtest_operator.api.v1alpha1 import environment, evaluation, sources
from simtest_operator.drivermodel import ExternalSut, Launch, Lifetime, SutConfig, Takeover
from simtest_operator.evaluation import DEFAULT_TIME_LIMIT, Criteria
from simtest_operator.scenarios import batching, globbing, specs
from simtest_operator.scenarios.pinned import PinnedScenario
from simtest_operator.settings import SimulationSettings


def selection(spec: sources.ScenarioSelection) -> specs.Selection:
    """The campaign's scenario selection."""
    selector = spec.selector
    return specs.Selection(
        sources=tuple(source(entry) for entry in spec.sources),
        include=tuple(spec.include),
        exclude=tuple(spec.exclude),
        selector=specs.Selector(
            tags=tuple(selector.match_tags) if selector else (),
            labels=dict(selector.match_labels) if selector else {},
        ),
        overrides=dict(spec.overrides),
    )


def source(spec: sources.ScenarioSource) -> specs.SourceSpec:
    """One source entry (the wire model guarantees exactly one kind is set)."""
    if spec.path is not None:
        return specs.PathSource(path=spec.path)
    if spec.git is not None:
        return specs.GitSource(url=spec.git.url, revision=spec.git.revision, path=spec.git.path)
    if spec.http is not None:
        return specs.HttpSource(url=spec.http.url, sha256=spec.http.sha256)
    if spec.graphql is not None:
        ref = spec.graphql.secret_ref
        return specs.GraphqlSource(
            endpoint=spec.graphql.endpoint,
            query=spec.graphql.query,
            variables=dict(spec.graphql.variables),
            secret=specs.SecretRef(name=ref.name, key=ref.key) if ref else None,
        )
    if spec.rest is not None:
        rest_ref = spec.rest.secret_ref
        return specs.RestSource(
            url=spec.rest.url,
            secret=specs.SecretRef(name=rest_ref.name, key=rest_ref.key) if rest_ref else None,
        )
    assert spec.config_map is not None
    return specs.ConfigMapSource(name=spec.config_map.name, keys=tuple(spec.config_map.keys))


def execution(spec: v1alpha1.ExecutionSpec) -> batching.ExecutionPolicy:
    """Batching, parallelism, time limit and retries."""
    return batching.ExecutionPolicy(
        batch_size=spec.batch_size,
        policy=batching.StartPolicy.BARRIER if spec.batch_barrier else batching.StartPolicy.WINDOW,
        max_parallel=spec.max_parallel,
        timeout_seconds=float(spec.timeout_seconds),
        retries=spec.retries,
    )


def criteria(spec: evaluation.EvaluationSpec, scenario_id: str) -> Criteria:
    """The criteria for one scenario: campaign-wide, then every matching override in order."""
    base = spec.criteria
    values: dict[str, object] = {
        "collision": base.collision is evaluation.CollisionPolicy.FORBIDDEN,
        "min_ttc": base.min_ttc,
        "min_thw": base.min_thw,
        "max_decel": base.max_deceleration,
        "off_road": base.off_road,
        "time_limit": base.complete_within or DEFAULT_TIME_LIMIT,
    }
    for override in spec.overrides:
        if not globbing.matches(scenario_id, override.scenarios):
            continue
        patch = override.criteria
        if patch.collision is not None:
            values["collision"] = patch.collision is evaluation.CollisionPolicy.FORBIDDEN
        for wire, domain in (
            ("min_ttc", "min_ttc"),
            ("min_thw", "min_thw"),
            ("max_deceleration", "max_decel"),
            ("off_road", "off_road"),
            ("complete_within", "time_limit"),
        ):
            value = getattr(patch, wire)
            if value is not None:
                values[domain] = value
    return Criteria(**values)  # type: ignore[arg-type]


def sut(spec: environment.SutConfig) -> SutConfig:
    """The stand-in system under test (identity and driver-model parameters)."""
    model = spec.driver_model
    return SutConfig(
        name=spec.name,
        version=spec.version,
        ego=spec.ego,
        takeover=Takeover(spec.takeover.value[0].lower() + spec.takeover.value[1:]),
        desired_speed=model.desired_speed,
        time_headway=model.time_headway,
        min_gap=model.min_gap,
        max_acceleration=model.max_acceleration,
        comfortable_deceleration=model.comfortable_deceleration,
        max_deceleration=model.max_deceleration,
        acc=model.acc,
        lane_keeping=model.lane_keeping,
        traffic_signals=model.traffic_signals,
        aeb=model.aeb.enabled,
        aeb_ttc_threshold=model.aeb.ttc_threshold,
        aeb_deceleration=model.aeb.deceleration,
        external=external_sut(spec.external, spec.config) if spec.external else None,
    )


def external_sut(spec: environment.ExternalSut, config: dict[str, str]) -> ExternalSut:
    """How the runner reaches an external SUT: a sidecar (image), an endpoint, or a process it
    starts next to the simulator (command only)."""
    launch = Launch.LOCAL
    if spec.endpoint is not None:
        launch = Launch.ENDPOINT
    elif spec.image is not None:
        launch = Launch.SIDECAR
    return ExternalSut(
        launch=launch,
        command=tuple(spec.command),
        endpoint=spec.endpoint,
        port=spec.port,
        image=spec.image,
        env=dict(spec.env),
        step_deadline=spec.step_deadline_milliseconds / 1000.0,
        startup_timeout=float(spec.startup_timeout_seconds),
        perception_range=spec.perception_range,
        config=dict(config),
        lifetime=Lifetime(spec.lifetime.value.lower()),
    )


def simulation(spec: environment.SimulatorSettings) -> SimulationSettings:
    """Step length, seed, recording rate and pace of the simulator stand-in."""
    return SimulationSettings(
        step_length=spec.step_length,
        seed=spec.seed,
        record_hz=spec.record_hz,
        real_time_factor=spec.real_time_factor,
    )


def pinned_to_wire(pinned: PinnedScenario) -> v1alpha1.FrozenScenario:
    """A frozen-list entry as it appears in ScenarioBatch and SimEnvironment specs."""
    return v1alpha1.FrozenScenario.model_validate(pinned.to_json())


def pinned_from_wire(wire: v1alpha1.FrozenScenario) -> PinnedScenario:
    """Inverse of :func:`pinned_to_wire`."""
    return PinnedScenario.from_json(wire.to_wire(), where=f"frozen scenario {wire.id}")
