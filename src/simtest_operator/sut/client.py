"""The simulator side of the SUT protocol: connect, handshake, then one lockstep exchange per
step with a deadline.

:class:`RemotePilot` is the engine's :class:`~simtest_operator.sim.sut.Pilot` for an external
SUT. Lockstep keeps runs deterministic: the simulation does not advance until the SUT answered
the step, and a SUT that answers late, wrongly or not at all ends the run with a
:class:`~simtest_operator.sut.errors.SutError` that names the cause (the runner turns it into an
``Error`` verdict). Round-trip times are kept for the bench and the result.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import socket
import time
from collections.abc import Callable, Mapping, Sequence
from types import TracebackType
from typing import TYPE_CHECKING, Any

from simtest_operator.sim.sut import Order, PilotView
from simtest_operator.snapshots import EntityState
from simtest_operator.sut import framing, messages
from simtest_operator.sut.errors import SutDeadlineError, SutError, SutProtocolError
from simtest_operator.sut.framing import Kind

if TYPE_CHECKING:
    from simtest_operator.opendrive import TrafficControl

CONNECT_POLL = 0.02
"""Seconds between connection attempts while the SUT starts (readiness polling)."""
LATE_GRACE_SECONDS = 1.0
"""After a missed step deadline, how much longer (at least) to wait to say by how much."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Identity:
    """What the SUT says about itself in READY (for the results)."""

    name: str = ""
    version: str = ""
    digest: str = ""
    answers: str = "MotionRequest"
    resets: bool = False
    """READY's ``reset``: the SUT starts every run afresh, so one process may serve many."""

    def describe(self) -> str:
        parts = [p for p in (self.name, self.version) if p]
        if self.digest:
            parts.append(self.digest)
        return " ".join(parts) or "unnamed SUT"


def parse_endpoint(endpoint: str) -> tuple[str, int]:
    """``host:port`` -> (host, port); ValueError with the bad text otherwise."""
    host, sep, port = endpoint.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"SUT endpoint {endpoint!r} is not host:port")
    return host.strip("[]"), int(port)


def connect(
    endpoint: str, *, timeout: float, alive: Callable[[], str | None] | None = None
) -> socket.socket:
    """Connect to the SUT, polling until it accepts or ``timeout`` passes (no blind sleep: each
    attempt either connects or is refused at once). ``alive`` (a callable returning an error
    text or None) lets a launcher stop waiting for a process that already died."""
    host, port = parse_endpoint(endpoint)
    deadline = time.monotonic() + timeout
    last = "no attempt"
    while True:
        if alive is not None:
            dead = alive()
            if dead:
                raise SutError(f"the SUT did not start: {dead}")
        try:
            sock = socket.create_connection((host, port), timeout=max(timeout, 0.1))
        except OSError as exc:
            last = exc.strerror or str(exc)
        else:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            return sock
        if time.monotonic() >= deadline:
            raise SutError(
                f"the SUT did not become ready at {endpoint} within {timeout:g} s ({last})"
            )
        time.sleep(CONNECT_POLL)


class RemotePilot:
    """One run's connection to an external SUT; use as a context manager."""

    __slots__ = (
        "_action_id",
        "_deadline",
        "_encoder",
        "_last_speed",
        "_sock",
        "failed",
        "identity",
        "postmortem",
        "round_trips",
        "step",
    )

    def __init__(
        self,
        sock: socket.socket,
        *,
        step_deadline: float,
        perception_range: float | None,
        map_reference: str = "map",
        signals: Sequence[TrafficControl] = (),
    ) -> None:
        self._sock = sock
        self._deadline = step_deadline
        self._encoder = messages.SensorViewEncoder(
            perception_range=perception_range, map_reference=map_reference, signals=signals
        )
        self._last_speed: float | None = None
        self._action_id = 0
        self.step = 0
        self.identity = Identity()
        self.round_trips: list[float] = []
        """Seconds from sending each step to its answer."""
        self.postmortem: Callable[[], str | None] | None = None
        """What happened to the SUT's process, for errors (set by the launcher)."""
        self.failed = False
        """Whether the SUT failed this run (a warm process is then not trusted with another)."""

    def handshake(self, hello: Mapping[str, Any], *, timeout: float) -> Identity:
        """Send HELLO and wait for READY (the SUT's start-up readiness check)."""
        try:
            return self._handshake(hello, timeout=timeout)
        except SutError as exc:
            raise self._explained(exc) from exc

    def drive(self, view: PilotView) -> Order:
        """One lockstep exchange: SensorView (and TrafficCommand) out, the order back."""
        try:
            return self._drive(view)
        except SutError as exc:
            raise self._explained(exc) from exc

    def _handshake(self, hello: Mapping[str, Any], *, timeout: float) -> Identity:
        payload = json.dumps({"protocol": framing.PROTOCOL_VERSION, **hello}).encode()
        framing.send(self._sock, Kind.HELLO, 0, payload)
        frame = self._receive(timeout, what="the handshake (READY)")
        if frame.kind is not Kind.READY:
            raise SutProtocolError(f"the SUT answered HELLO with {frame.kind.name}, not READY")
        try:
            ready = json.loads(frame.payload)
        except ValueError as exc:
            raise SutProtocolError(f"the SUT's READY is not JSON: {exc}") from exc
        if not isinstance(ready, dict):
            raise SutProtocolError("the SUT's READY is not a JSON object")
        if ready.get("protocol") != framing.PROTOCOL_VERSION:
            raise SutProtocolError(
                f"the SUT speaks protocol {ready.get('protocol')!r}, "
                f"the simulator {framing.PROTOCOL_VERSION}"
            )
        answers = str(ready.get("answers", "MotionRequest"))
        if answers not in ("MotionRequest", "TrafficUpdate"):
            raise SutProtocolError(f"the SUT answers {answers!r}, not MotionRequest/TrafficUpdate")
        self.identity = Identity(
            name=str(ready.get("name", "")),
            version=str(ready.get("version", "")),
            digest=str(ready.get("digest", "")),
            answers=answers,
            resets=ready.get("reset") is True,
        )
        return self.identity

    def _drive(self, view: PilotView) -> Order:
        snapshot = view.snapshot
        ego = _find(snapshot.entities, view.ego_id)
        self.step += 1
        nanos = round(snapshot.time * 1e9)
        out = b""
        if view.set_speed != self._last_speed:
            self._last_speed = view.set_speed
            self._action_id += 1
            command = messages.traffic_command(
                nanos=nanos, ego_id=ego.id, action_id=self._action_id, target_speed=view.set_speed
            )
            out = framing.encode(Kind.TRAFFIC_COMMAND, self.step, command)
        out += framing.encode(Kind.SENSOR_VIEW, self.step, self._encoder.encode(snapshot, ego))
        sent = time.perf_counter()
        try:
            self._sock.sendall(out)
        except OSError as exc:
            raise SutError(
                f"the SUT is gone at step {self.step} (t={snapshot.time:.3f} s): "
                f"{exc.strerror or exc}"
            ) from exc
        frame = self._receive(
            self._deadline, what=f"step {self.step} (t={snapshot.time:.3f} s)", step=True
        )
        self.round_trips.append(time.perf_counter() - sent)
        if frame.sequence != self.step:
            raise SutProtocolError(
                f"the SUT answered step {frame.sequence} when step {self.step} was asked"
            )
        try:
            if frame.kind is Kind.MOTION_REQUEST:
                return messages.decode_motion_request(frame.payload, ego, nanos=nanos, dt=view.dt)
            if frame.kind is Kind.TRAFFIC_UPDATE:
                return messages.decode_traffic_update(frame.payload, ego, dt=view.dt)
        except ValueError as exc:
            raise SutProtocolError(
                f"the SUT's {frame.kind.name} at step {self.step} is malformed: {exc}"
            ) from exc
        raise SutProtocolError(f"the SUT answered step {self.step} with {frame.kind.name}")

    def _receive(self, timeout: float, *, what: str, step: bool = False) -> framing.Frame:
        self._sock.settimeout(timeout)
        asked = time.perf_counter()
        try:
            frame = framing.receive(self._sock)
        except TimeoutError:
            late = f": {self._lateness(timeout, asked)}" if step else ""
            raise SutDeadlineError(
                f"the SUT missed the {timeout * 1000:g} ms deadline for {what}{late}"
            ) from None
        except SutError as exc:
            raise type(exc)(f"{exc} during {what}") from exc
        if frame.kind is Kind.ERROR:
            reason = frame.payload.decode("utf-8", "replace")
            raise SutError(f"the SUT reported an error during {what}: {reason}")
        return frame

    def _lateness(self, timeout: float, asked: float) -> str:
        """How late the answer came: wait a while longer (only once the run has failed) so the
        SUT's developer learns whether it was a little slow or not answering at all."""
        grace = max(LATE_GRACE_SECONDS, 10 * timeout)
        self._sock.settimeout(grace)
        try:
            framing.receive(self._sock)
        except (TimeoutError, SutError):
            return f"no answer within {(timeout + grace) * 1000:g} ms"
        late = (time.perf_counter() - asked - timeout) * 1000
        return f"the answer came {late:.0f} ms late"

    def _explained(self, exc: SutError) -> SutError:
        """``exc`` with what the SUT's process did or said last (every SUT error says it)."""
        self.failed = True
        fate = self.postmortem() if self.postmortem is not None else None
        return type(exc)(f"{exc}; {fate}") if fate else exc

    def close(self) -> None:
        """Say GOODBYE (best effort) and close the connection."""
        with contextlib.suppress(OSError):
            self._sock.sendall(framing.encode(Kind.GOODBYE, self.step))
        self._sock.close()

    def __enter__(self) -> RemotePilot:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()


def _find(entities: tuple[EntityState, ...], ident: int) -> EntityState:
    for state in entities:
        if state.id == ident:
            return state
    raise SutError(f"the ego (id {ident}) is not in the world snapshot")
