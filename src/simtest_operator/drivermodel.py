"""The ego driver model: its configuration and its longitudinal and lateral decisions.

Longitudinal control is the Intelligent Driver Model (Treiber et al. 2000) when adaptive cruise
control is on (follow the vehicle ahead with a time gap) and plain cruise control when it is off;
automatic emergency braking (AEB) overrides both when the in-path time to collision drops below
its threshold. Laterally the model steers back to the lane centre as a vehicle can: the heading
it wants removes the offset with a time constant, and the heading turns towards it no faster
than a kinematic bicycle with its steering limit and a lane-keeping lateral acceleration allow
(so an ego off centre at walking speed creeps back instead of swinging round). With lane keeping
off it follows the lane at its offset. Two configurations therefore produce different behaviour
on the same scenario, which is the point of testing a SUT.

:class:`SutConfig` mirrors the campaign's ``spec.environment.sut.driverModel`` (``api`` converts
into it), plus how and when the ego is handed to the model (:class:`Takeover`) and where an
external SUT comes from (:class:`ExternalSut`). The values sit below ``api``, ``sim`` and ``sut``
and import nothing, so the operator and the reference SUT use them without loading the simulator.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Mapping, Sequence
from pathlib import Path


class Takeover(enum.StrEnum):
    """When the driver model takes the ego over from the storyboard."""

    ON_CONTROLLER = "onController"
    """When an ActivateControllerAction activates the ego's controller, or from the start when the
    ego has an ObjectController (OpenSCENARIO semantics; scripted otherwise)."""
    AFTER_INIT = "afterInit"
    """Right after the Init actions: the storyboard only sets the ego's start state and speed."""
    NEVER = "never"
    """The ego stays scripted (reproduces the reference player; SUT settings have no effect)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SutConfig:
    """Parameters of the ego driver model (defaults equal the api's defaults)."""

    name: str = "idm-driver"
    version: str = "0.0.0"
    ego: str | None = None
    """Entity that is the ego; None picks (under ScenarioRunner's rules) the vehicle typed
    ``ego_vehicle``, else ``Ego``/``ego``/``hero``, else the first vehicle."""
    takeover: Takeover = Takeover.ON_CONTROLLER
    desired_speed: float | None = None
    """Cruise speed (m/s); None keeps the speed the scenario gives the ego."""
    time_headway: float = 1.5
    """IDM T / ACC time gap (s)."""
    min_gap: float = 2.0
    """IDM s0 (m)."""
    max_acceleration: float = 2.0
    """IDM a (m/s^2)."""
    comfortable_deceleration: float = 3.0
    """IDM b (m/s^2)."""
    max_deceleration: float = 8.0
    """Physical braking limit of the controller (m/s^2)."""
    acc: bool = True
    """Follow the vehicle ahead (IDM); off: constant-speed cruise, blind to traffic."""
    lane_keeping: bool = True
    """Steer back to the lane centre; off: hold the heading."""
    aeb: bool = True
    """Automatic emergency braking."""
    aeb_ttc_threshold: float = 1.5
    """In-path TTC (s) below which AEB brakes."""
    aeb_deceleration: float = 8.0
    """AEB braking (m/s^2)."""
    sensor_range: float = 200.0
    """How far ahead (m) the model sees other road users."""
    traffic_signals: bool = True
    """Obey the map's traffic lights and stop signs (red: stop at the line, yellow: stop if it
    can comfortably, stop sign: stand still at the line, then go); off: drive through them."""
    external: ExternalSut | None = None
    """Where an external SUT runs; None drives the ego with the in-process model above."""


class Launch(enum.StrEnum):
    """How the runner reaches an external SUT."""

    LOCAL = "local"
    """Start ``command`` as a local process for every run and connect to it."""
    SIDECAR = "sidecar"
    """A container next to the simulator (``SIMTEST_SUT_ENDPOINT`` in the pod says where);
    outside a pod the runner starts ``command`` locally instead."""
    ENDPOINT = "endpoint"
    """Connect to ``endpoint``; nothing is started."""


class Lifetime(enum.StrEnum):
    """How long a SUT process the runner starts lives."""

    SCENARIO = "scenario"
    """Started for each run, stopped after it."""
    WORKER = "worker"
    """Kept warm by the local worker process across its runs while the SUT resets itself
    between them (READY ``"reset": true``)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ExternalSut:
    """An external system under test reached through the OSI SUT protocol."""

    launch: Launch
    command: tuple[str, ...] = ()
    """Process to start (local) or the sidecar's command; gets ``SIMTEST_SUT_PORT``."""
    endpoint: str | None = None
    """``host:port`` to connect to."""
    port: int = 7460
    """Port a sidecar listens on."""
    image: str | None = None
    """Sidecar image (identity for the results)."""
    image_id: str = ""
    """``repo@sha256:…`` of ``image`` where the runner can tell (a digest-pinned reference, the
    local build index); empty: unknown here (in a pod the operator adds what the kubelet ran)."""
    env: Mapping[str, str] = dataclasses.field(default_factory=dict)
    step_deadline: float = 0.1
    """Seconds the SUT may take to answer one step before the run ends Error."""
    startup_timeout: float = 60.0
    """Seconds the SUT may take to accept the connection and answer the handshake."""
    perception_range: float | None = None
    """Radius (m) around the ego beyond which other objects are left out of the SensorView."""
    config: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """Free-form configuration sent to the SUT in the handshake."""
    lifetime: Lifetime = Lifetime.SCENARIO
    """How long a process started from ``command`` lives."""
    output_dir: Path | None = None
    """Folder where a pod's sidecars print (``<container>.log`` each): what they printed during
    a run becomes its ``sut.log``. None: nothing there to keep (a local process's output is
    kept from its pipe)."""


IDM_DELTA = 4.0
"""IDM acceleration exponent (the usual value)."""

LANE_KEEPING_TIME = 1.0
"""Time constant (s) with which lane keeping removes a lateral offset."""
LANE_KEEPING_LATERAL_ACCELERATION = 3.0
"""m/s^2: the most lateral acceleration lane keeping steers with (ISO 11270's limit for lane
keeping assistance); it caps the yaw rate at speed."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Steering:
    """What the vehicle can steer: a kinematic bicycle with a front-wheel angle limit."""

    wheelbase: float = 2.8
    """m between the axles (a passenger car's when the file declares no axles)."""
    max_angle: float = 0.5
    """rad: the front wheels' largest angle (OpenSCENARIO's usual ``maxSteering``)."""

    def max_yaw_rate(self, speed: float) -> float:
        """rad/s the vehicle can turn at ``speed``: its tightest circle, and no faster than
        lane keeping's lateral acceleration allows (0 at standstill: a car turns by moving)."""
        v = abs(speed)
        if v <= 0.0:
            return 0.0
        geometric = v * math.tan(self.max_angle) / self.wheelbase
        return min(geometric, LANE_KEEPING_LATERAL_ACCELERATION / v)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Leader:
    """The nearest road user ahead in the ego's path, as the ego perceives it."""

    gap: float
    """Free-space distance (m) bumper to bumper."""
    speed: float
    """Its speed along the ego's heading (m/s)."""


class Aspect(enum.StrEnum):
    """What a traffic light shows, as far as a driver cares."""

    RED = "red"
    YELLOW = "yellow"
    GREEN = "green"
    UNKNOWN = "unknown"
    """Off, flashing, or never set: the light does not regulate (go)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SignalAhead:
    """A stop line ahead in the driver's path: a traffic light's or a stop sign's."""

    key: str
    """Which signal (the OpenDRIVE id): a stop sign is served once per approach."""
    distance: float
    """Metres from the front bumper to the line along the path."""
    stop_sign: bool = False
    aspect: Aspect = Aspect.UNKNOWN
    """The light's aspect (stop signs: unused)."""


STOP_MARGIN = 0.5
"""Metres before the line where the front bumper comes to rest."""
STOP_HOLD = 1.5
"""Metres of gap to that point within which a stopped vehicle holds instead of creeping on;
a standstill that near the line serves a stop sign."""
STANDSTILL = 0.1
"""m/s below which a vehicle stands still at a stop sign (ScenarioRunner's RunningStopTest)."""


def signal_horizon(speed: float, config: SutConfig) -> float:
    """How far ahead (m) stop lines matter at ``speed``: the comfortable stopping distance,
    plus a few seconds of travel and a margin (a light further on needs no braking yet)."""
    v = max(speed, 0.0)
    reach = v * v / (2.0 * config.comfortable_deceleration) + 3.0 * v + 30.0
    return min(reach, config.sensor_range)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Command:
    """What the driver model wants this step."""

    acceleration: float
    aeb_active: bool


def _stopping(speed: float, gap: float, dt: float, comfortable: float) -> float:
    """Acceleration that stops within ``gap`` metres: none (inf) while cruising on one more
    step would still leave room to stop at ``comfortable`` deceleration, then the constant
    deceleration that ends exactly there (about ``comfortable``: braking starts as late as
    comfort allows, not with IDM's early, gentle approach); held still once there."""
    if gap <= STOP_HOLD and speed < STANDSTILL:
        return -comfortable
    if gap <= 0.0:
        return -math.inf
    room = gap - speed * dt
    if room > 0.0 and speed * speed < 2.0 * comfortable * room:
        return math.inf
    return -speed * speed / (2.0 * gap)


class DriverModel:
    """Longitudinal decision of the SUT for one ego, with AEB latch state."""

    __slots__ = ("_aeb_latched", "_served", "_yellow", "config", "follows_limits", "set_speed")

    def __init__(self, config: SutConfig, *, set_speed: float) -> None:
        self.config = config
        self.set_speed = config.desired_speed if config.desired_speed is not None else set_speed
        """Current cruise target; scenario SpeedActions on the ego change it (driver request)."""
        self.follows_limits = False
        """Set for CARLA's autopilot: the road's speed limit is the set speed, not requests."""
        self._aeb_latched = False
        self._served: set[str] = set()
        """Stop signs stood at on the current approach (go on through them)."""
        self._yellow: dict[str, bool] = {}
        """Per light seen yellow: whether the driver decided to stop (kept while yellow)."""

    def command(
        self,
        *,
        speed: float,
        leader: Leader | None,
        signals: Sequence[SignalAhead] = (),
        dt: float = 0.0,
    ) -> Command:
        """Acceleration for this step given the ego speed, the perceived leader and the stop
        lines ahead (``dt``: the step, for braking that starts in time)."""
        cfg = self.config
        if self.set_speed > 0.0:
            free = cfg.max_acceleration * (1.0 - (max(speed, 0.0) / self.set_speed) ** IDM_DELTA)
        else:
            # A set speed of 0 asks the driver to stop (comfortably) and stay stopped.
            free = -cfg.comfortable_deceleration if speed > 0.0 else 0.0
        acceleration = free
        if leader is not None and cfg.acc:
            closing = speed - leader.speed
            wanted = cfg.min_gap + max(
                0.0,
                speed * cfg.time_headway
                + speed
                * closing
                / (2.0 * math.sqrt(cfg.max_acceleration * cfg.comfortable_deceleration)),
            )
            acceleration = free - cfg.max_acceleration * (wanted / max(leader.gap, 0.1)) ** 2
        if signals or self._served or self._yellow:
            acceleration = min(acceleration, self._obey(speed, signals, dt))
        acceleration = max(acceleration, -cfg.max_deceleration)
        aeb = self._aeb(speed=speed, leader=leader)
        if aeb:
            acceleration = min(acceleration, -cfg.aeb_deceleration)
        return Command(acceleration=acceleration, aeb_active=aeb)

    def _obey(self, speed: float, signals: Sequence[SignalAhead], dt: float) -> float:
        """The most acceleration the stop lines ahead allow (inf: no limit). Red: stop before
        the line unless even full braking cannot any more (then it is committed: go, not stop
        in the junction); yellow: the dilemma rule, decided when first seen yellow: stop if
        comfortable braking can, else go; a stop sign: stop, then go once stood still near
        its line; green or unknown: go."""
        cfg = self.config
        seen = {signal.key for signal in signals}
        self._served &= seen
        self._yellow = {key: stop for key, stop in self._yellow.items() if key in seen}
        limit = math.inf
        v = max(speed, 0.0)
        for signal in sorted(signals, key=lambda signal: signal.distance):
            gap = signal.distance - STOP_MARGIN
            if signal.stop_sign:
                if signal.key in self._served:
                    continue
                if v < STANDSTILL and gap <= STOP_HOLD:
                    self._served.add(signal.key)
                    continue
            elif signal.aspect is Aspect.YELLOW:
                if signal.key not in self._yellow:
                    needed = v * v / (2.0 * max(signal.distance, 1e-6))
                    self._yellow[signal.key] = needed <= cfg.comfortable_deceleration
                if not self._yellow[signal.key]:
                    continue
            elif signal.aspect is Aspect.RED:
                self._yellow.pop(signal.key, None)
                if v * v > 2.0 * cfg.max_deceleration * max(signal.distance, 0.0):
                    continue
            else:
                self._yellow.pop(signal.key, None)
                continue
            limit = min(limit, _stopping(v, gap, dt, cfg.comfortable_deceleration))
        return limit

    def _aeb(self, *, speed: float, leader: Leader | None) -> bool:
        cfg = self.config
        if not cfg.aeb or speed <= 0.0:
            self._aeb_latched = False
            return False
        closing = speed - leader.speed if leader is not None else 0.0
        ttc = leader.gap / closing if leader is not None and closing > 0.0 else math.inf
        if ttc < cfg.aeb_ttc_threshold:
            self._aeb_latched = True
        elif self._aeb_latched and (leader is None or closing <= 0.0):
            self._aeb_latched = False
        return self._aeb_latched

    def steer(
        self, *, offset: float, heading: float, speed: float, dt: float, steering: Steering
    ) -> float:
        """Lane keeping: the relative heading (rad, towards +offset) for the step to ``dt``.

        ``offset`` is the distance from the lane centre (m), ``heading`` the vehicle's heading
        relative to the lane now and ``speed`` its speed over the step; the vehicle moves
        ``speed * sin(result) * dt`` across the lane. The wish removes the offset with
        :data:`LANE_KEEPING_TIME` (as fast as the offset decays), never turned more than the
        vehicle can turn back before the centre; the heading moves towards it no faster than
        ``steering`` allows at ``speed``. Off: the lane's heading.
        """
        if not self.config.lane_keeping or speed <= 0.0 or dt <= 0.0:
            return 0.0
        wanted_rate = offset * math.expm1(-dt / LANE_KEEPING_TIME) / dt
        wanted = math.asin(max(-1.0, min(1.0, wanted_rate / speed)))
        yaw_rate = steering.max_yaw_rate(speed)
        # Turning back at yaw_rate from heading h covers about speed * h^2 / (2 yaw_rate) sideways.
        unwind = math.sqrt(2.0 * yaw_rate * abs(offset) / speed)
        wanted = max(-unwind, min(unwind, wanted))
        turn = yaw_rate * dt
        return heading + max(-turn, min(turn, wanted - heading))
