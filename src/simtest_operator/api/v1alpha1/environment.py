"""How each scenario's simulation environment is composed: template, values, SUT, simulator."""

from __future__ import annotations

import enum
import re
from typing import Annotated, Any, ClassVar

from pydantic import Field, StringConstraints, model_validator

from simtest_operator.api.v1alpha1.common import ApiModel, DnsLabel, Quantity, cel

PositiveFloat = Annotated[float, Field(gt=0)]


class Provisioner(enum.StrEnum):
    """How a SimEnvironment is brought up."""

    POD = "Pod"
    """The operator creates the rendered simulator pod directly (fast path)."""
    HELMFILE = "Helmfile"
    """A Job applies the rendered helmfile with the real helmfile binary (charted stacks)."""


class AebConfig(ApiModel):
    """Autonomous emergency braking of the driver model."""

    enabled: bool = True
    """Whether AEB may override the longitudinal controller."""
    ttc_threshold: Annotated[float, Field(gt=0, le=10)] = 1.5
    """Time to collision (s) below which AEB brakes."""
    deceleration: Annotated[float, Field(gt=0, le=15)] = 8.0
    """Braking deceleration (m/s^2) AEB applies."""


class DriverModel(ApiModel):
    """The stand-in system under test: IDM/ACC longitudinal control, lane keeping, AEB."""

    desired_speed: Annotated[float, Field(ge=0, le=100)] | None = None
    """Cruise speed (m/s); unset keeps the speed the scenario gives the ego at start."""
    time_headway: Annotated[float, Field(gt=0, le=10)] = 1.5
    """Desired time gap (s) to the vehicle ahead (IDM T / ACC time gap)."""
    min_gap: Annotated[float, Field(ge=0, le=50)] = 2.0
    """Standstill distance (m) to the vehicle ahead (IDM s0)."""
    max_acceleration: Annotated[float, Field(gt=0, le=10)] = 2.0
    """Maximum acceleration (m/s^2) (IDM a)."""
    comfortable_deceleration: Annotated[float, Field(gt=0, le=10)] = 3.0
    """Comfortable deceleration (m/s^2) (IDM b)."""
    max_deceleration: Annotated[float, Field(gt=0, le=15)] = 8.0
    """Physical braking limit (m/s^2)."""
    acc: bool = True
    """Adaptive cruise control: follow the vehicle ahead; off means constant-speed cruise."""
    lane_keeping: bool = True
    """Keep the lane centre; off lets the ego hold its heading."""
    traffic_signals: bool = True
    """Obey the map's traffic lights and stop signs (stop at red, stop on yellow when it
    comfortably can, stand still at a stop sign, then go); off drives through them."""
    aeb: AebConfig = Field(default_factory=AebConfig)
    """Emergency braking."""


class Takeover(enum.StrEnum):
    """When the driver model takes the ego over from the storyboard."""

    ON_CONTROLLER = "OnController"
    """When the scenario activates the ego's controller (OpenSCENARIO semantics)."""
    AFTER_INIT = "AfterInit"
    """Right after the Init actions, for scenarios that script the ego without a controller."""
    NEVER = "Never"
    """The ego stays scripted; the SUT settings have no effect (reproduces a reference player)."""


class SutLifetime(enum.StrEnum):
    """How long a SUT process the runner starts (``command`` without ``image``/``endpoint``,
    or a sidecar's command under ``simtest run``) lives."""

    SCENARIO = "Scenario"
    """Started for each scenario and stopped after it."""
    WORKER = "Worker"
    """Started once per local worker process and kept warm: it serves that worker's scenarios
    one after the other when its READY says ``"reset": true`` (it starts each run afresh);
    a SUT that does not say so, or that failed a run, is restarted for the next."""


ENDPOINT = r"^[A-Za-z0-9]([-A-Za-z0-9.]*[A-Za-z0-9])?:[0-9]{1,5}$"
ENV_NAME = r"^[A-Za-z_][A-Za-z0-9_]*$"


class SutResourceList(ApiModel):
    """CPU and memory of the SUT sidecar."""

    cpu: Quantity = "500m"
    """CPU, e.g. ``250m`` or ``1``."""
    memory: Quantity = "256Mi"
    """Memory, e.g. ``256Mi``."""


class SutResources(ApiModel):
    """Requests and limits of the SUT sidecar (limits default to the requests)."""

    requests: SutResourceList = Field(default_factory=SutResourceList)
    """What the scheduler reserves for the SUT."""
    limits: SutResourceList | None = None
    """Upper bounds; unset means equal to the requests."""


class ExternalSut(ApiModel):
    """A system under test outside the simulator, speaking the OSI SUT protocol
    (docs/sut-interface.md). ``image``: a sidecar container in the simulator pod; ``endpoint``:
    a SUT already listening somewhere; neither: ``command`` started next to the simulator."""

    cel_rules: ClassVar[tuple[dict[str, str], ...]] = (
        cel(
            "!(has(self.image) && has(self.endpoint))",
            "set image (sidecar) or endpoint, not both",
        ),
        cel(
            "has(self.image) || has(self.endpoint) "
            "|| (has(self.command) && size(self.command) > 0)",
            "an external SUT needs an image, an endpoint or a command",
        ),
    )

    image: Annotated[str, StringConstraints(min_length=1, max_length=512)] | None = None
    """Container image of the SUT, run as a sidecar of the simulator pod."""
    command: Annotated[
        list[Annotated[str, StringConstraints(min_length=1, max_length=1024)]],
        Field(max_length=64),
    ] = Field(default_factory=list)
    """Command of the sidecar (default: the image's entrypoint), or the process the runner
    starts next to the simulator when no image is set (``simtest run`` starts it locally for a
    sidecar SUT too). It gets ``SIMTEST_SUT_PORT``; ``{port}`` in an argument is replaced."""
    env: Annotated[
        dict[str, Annotated[str, StringConstraints(max_length=4096)]], Field(max_length=64)
    ] = Field(default_factory=dict)
    """Environment variables of the SUT (names: letters, digits, ``_``)."""
    resources: SutResources = Field(default_factory=SutResources)
    """Requests and limits of the sidecar (they count towards the pod's)."""
    port: Annotated[int, Field(ge=1024, le=65535)] = 7460
    """Port the sidecar listens on, or the SUT of a composed stack and its Service (template
    ``composed-sut``)."""
    endpoint: Annotated[str, StringConstraints(pattern=ENDPOINT, max_length=260)] | None = None
    """``host:port`` of a SUT that is already running; nothing is started. In a pod whose
    template names the SUT's address (``composed-sut``: the Service of the stack it composes),
    that address wins and this one serves ``simtest run``."""
    step_deadline_milliseconds: Annotated[int, Field(ge=1, le=60000)] = 100
    """Time the SUT has to answer one step; a late answer ends the run Error."""
    startup_timeout_seconds: Annotated[int, Field(ge=1, le=600)] = 60
    """Time the SUT has to accept the connection and answer the handshake."""
    perception_range: Annotated[float, Field(gt=0, le=10000)] | None = None
    """Objects farther than this (m) from the ego are left out of the SensorView."""
    lifetime: SutLifetime = SutLifetime.SCENARIO
    """How long a SUT process the runner starts lives: one scenario, or one local worker
    (kept warm between scenarios; in a pod, a sidecar already lives as long as the pod)."""

    @model_validator(mode="after")
    def _one_way_to_reach(self) -> ExternalSut:
        bad = sorted(name for name in self.env if not re.fullmatch(ENV_NAME, name))
        if bad:
            raise ValueError(f"env names must match {ENV_NAME}: {', '.join(bad)}")
        if self.image is not None and self.endpoint is not None:
            raise ValueError("set image (sidecar) or endpoint, not both")
        if self.image is None and self.endpoint is None and not self.command:
            raise ValueError("an external SUT needs an image, an endpoint or a command")
        return self


class SutConfig(ApiModel):
    """The system under test: identity for the results and the driver-model parameters."""

    name: DnsLabel = "idm-driver"
    """Name of the SUT, stored with every result."""
    version: Annotated[str, StringConstraints(max_length=128)] = "0.0.0"
    """Version of the SUT, stored with every result so two SUT versions can be compared."""
    image: Annotated[str, StringConstraints(max_length=512)] | None = None
    """Container image of the SUT's own workload, rendered into the environment's values: a
    K8s-ROS release (``default``, ``ros2``) or the stack the simulator connects to
    (``composed-sut``)."""
    ego: Annotated[str, StringConstraints(min_length=1, max_length=256)] | None = None
    """Scenario entity that is the system under test; unset picks ``Ego``/``ego``/``hero``,
    else the first vehicle."""
    takeover: Takeover = Takeover.ON_CONTROLLER
    """When the driver model takes the ego over from the storyboard."""
    driver_model: DriverModel = Field(default_factory=DriverModel)
    """Parameters of the stand-in driver model that drives the ego."""
    config: dict[str, str] = Field(default_factory=dict)
    """Free-form configuration override passed to the SUT components (an external SUT receives
    it in the protocol's handshake; its hash is stored with every result)."""
    external: ExternalSut | None = None
    """An external SUT behind the OSI SUT protocol; unset drives the ego with the in-process
    driver model."""


class SimulatorSettings(ApiModel):
    """Settings of the SUMO-backed simulator stand-in."""

    cel_rules: ClassVar[tuple[dict[str, str], ...]] = (
        # The API server compares an integer (`stepLength: 0`) with the minimum cast to an
        # integer (0), so the schema's minimum alone lets 0 through.
        cel(
            "!has(self.stepLength) || self.stepLength >= 0.001",
            "stepLength must be at least 0.001 s",
            field_path=".stepLength",
        ),
    )

    image: Annotated[str, StringConstraints(max_length=512)] = (
        "ghcr.io/simtest-dev/simtest-runner:0.1.0"
    )
    """Runner image the simulator pod runs."""
    # `1e-300` once passed and made every scenario `Error`, retried (issue 29).
    step_length: Annotated[float, Field(ge=0.001, le=0.5)] = 0.05
    """Simulation step (s); at least 1 ms, SUMO's time resolution (a shorter step rounds to 0)."""
    real_time_factor: Annotated[float, Field(ge=0)] = 0.0
    """Pace relative to wall time; 0 runs as fast as possible."""
    seed: Annotated[int, Field(ge=0, le=2**31 - 1)] = 42
    """Seed for the simulator and every random choice, for reproducible runs."""
    record: bool = True
    """Write an omega-prime (OSI ground truth) MCAP recording per run."""
    record_hz: Annotated[float, Field(ge=10, le=100)] = 10.0
    """Recording rate (Hz); omega-prime requires at least 10."""


class EnvironmentSpec(ApiModel):
    """The environment every scenario runs in: the "dynamic Helmfile" of the paper."""

    template: DnsLabel = "default"
    """Environment template: a folder under ``helm-templates/``."""
    provisioner: Provisioner = Provisioner.POD
    """Pod (direct, fast) or Helmfile (apply the rendered helmfile in a Job)."""
    values: dict[str, Any] = Field(default_factory=dict)
    """Helm values merged over the template's defaults for every scenario."""
    sut: SutConfig = Field(default_factory=SutConfig)
    """System under test."""
    simulator: SimulatorSettings = Field(default_factory=SimulatorSettings)
    """Simulator settings."""
