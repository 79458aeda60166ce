"""How each scenario's simulation environment is composed: template, values, SUT, simulator."""

from __future__ import annotations

import enum
from typing import Annotated, Any

from pydantic import Field, StringConstraints

from simtest_operator.api.v1alpha1.common import ApiModel, DnsLabel

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


class SutConfig(ApiModel):
    """The system under test: identity for the results and the driver-model parameters."""

    name: DnsLabel = "idm-driver"
    """Name of the SUT, stored with every result."""
    version: Annotated[str, StringConstraints(max_length=128)] = "0.0.0"
    """Version of the SUT, stored with every result so two SUT versions can be compared."""
    image: Annotated[str, StringConstraints(max_length=512)] | None = None
    """Container image of an external SUT component, rendered into the environment's values."""
    ego: Annotated[str, StringConstraints(min_length=1, max_length=256)] | None = None
    """Scenario entity that is the system under test; unset picks ``Ego``/``ego``/``hero``,
    else the first vehicle."""
    takeover: Takeover = Takeover.ON_CONTROLLER
    """When the driver model takes the ego over from the storyboard."""
    driver_model: DriverModel = Field(default_factory=DriverModel)
    """Parameters of the stand-in driver model that drives the ego."""
    config: dict[str, str] = Field(default_factory=dict)
    """Free-form configuration override passed to the SUT components."""


class SimulatorSettings(ApiModel):
    """Settings of the SUMO-backed simulator stand-in."""

    image: Annotated[str, StringConstraints(max_length=512)] = (
        "ghcr.io/simtest-dev/simtest-runner:0.1.0"
    )
    """Runner image the simulator pod runs."""
    step_length: Annotated[float, Field(gt=0, le=0.5)] = 0.05
    """Simulation step (s)."""
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
