"""The external SUT of one run, as the runner sees it: connect it to the simulation before the
first step, name it in the results, release it afterwards, and report its round trips and the
real-time factor the run achieved.

The in-process driver model (``sut.external`` unset) needs none of this: :class:`SutLink` then
does nothing, so default runs keep their speed and results.
"""

from __future__ import annotations

import contextlib
import dataclasses
import time
from collections.abc import Mapping, MutableMapping
from pathlib import Path

from simtest_operator import provenance
from simtest_operator.drivermodel import Launch
from simtest_operator.settings import Settings, SimulationSettings
from simtest_operator.sim import Simulation, SutConfig
from simtest_operator.sut import client, launching, runs

KEEP_UP_TOLERANCE = 0.95
"""A paced run that achieves less than this share of its real-time factor fell behind."""


def with_image_id(sut: SutConfig, index: Path) -> SutConfig:
    """``sut`` naming the digest of its image where this machine can tell: from a reference
    pinned by digest, else from the build script's ``index``; else it stays unknown (in a pod
    the operator records the digest the kubelet reports)."""
    external = sut.external
    if external is None or not external.image or external.image_id:
        return sut
    found = provenance.pinned_image_id(external.image) or provenance.built_image_id(
        external.image, index
    )
    return dataclasses.replace(sut, external=dataclasses.replace(external, image_id=found))


def reached_here(sut: SutConfig, settings: Settings) -> SutConfig:
    """``sut`` as this machine reaches it, for the run requests: its image digest where known
    (:func:`with_image_id`) and, for a ``sidecar`` or ``endpoint`` SUT, the endpoint the settings
    name (``SIMTEST_SUT_ENDPOINT``: a pod's template knows where its SUT listens), which wins
    over the campaign's, and the folder the pod's sidecars print into
    (``SIMTEST_SUT_OUTPUT_DIR``)."""
    sut = with_image_id(sut, settings.cache.image_index)
    external = sut.external
    if external is None or external.launch not in (Launch.SIDECAR, Launch.ENDPOINT):
        return sut
    located = dataclasses.replace(
        external,
        endpoint=settings.sut_endpoint or external.endpoint,
        output_dir=settings.sut_output or external.output_dir,
    )
    return sut if located == external else dataclasses.replace(sut, external=located)


class SutLink:
    """Opens the external SUT for a run (if any) and closes it; use :meth:`attach` then
    :meth:`close`."""

    __slots__ = ("_closing", "_pilot", "_processes", "_stack", "sut")

    def __init__(self, sut: SutConfig, processes: launching.SutProcesses | None = None) -> None:
        self.sut = sut
        self._processes = processes
        self._stack = contextlib.ExitStack()
        self._pilot: client.RemotePilot | None = None
        self._closing = 0.0

    def attach(
        self,
        simulation: Simulation,
        *,
        scenario_id: str,
        settings: SimulationSettings,
        map_reference: str,
        versions: MutableMapping[str, str],
        log: Path | None = None,
    ) -> None:
        """Start/connect the SUT, handshake and let it drive the ego (SutError on failure).

        ``versions`` names the configured SUT before it is reached, so a start-up error says
        which SUT and configuration failed; a SUT process started here leaves its output in
        ``log``.
        """
        external = self.sut.external
        if external is None or simulation.ego is None:
            return
        versions.update(runs.provenance(self.sut, None))
        hello = runs.hello(
            self.sut,
            ego_id=simulation.world.actors[simulation.ego].id,
            step=settings.step_length,
            scenario_id=scenario_id,
            seed=settings.seed,
        )
        self._pilot = self._stack.enter_context(
            launching.open_pilot(
                external,
                hello=hello,
                map_reference=map_reference,
                log=log,
                processes=self._processes,
                signals=simulation.world.signal_index.controls,
            )
        )
        simulation.attach_pilot(self._pilot)
        versions.update(runs.provenance(self.sut, self._pilot.identity))

    def close(self) -> None:
        """Say goodbye and stop a local SUT process (timed: not part of the stepping loop)."""
        started = time.perf_counter()
        self._stack.close()
        self._closing = time.perf_counter() - started

    def metrics(self, *, simulated: float, loop_seconds: float, pace: float) -> Mapping[str, float]:
        """Round trips of the SUT and the real-time factor of the stepping loop
        (``loop_seconds`` may include :meth:`close`, which is taken out)."""
        out: dict[str, float] = {}
        loop_seconds -= self._closing
        if self._pilot is not None:
            out.update(runs.round_trip_metrics(self._pilot.round_trips))
        if loop_seconds > 0 and simulated > 0 and (pace > 0 or self._pilot is not None):
            achieved = simulated / loop_seconds
            out["loopRealTimeFactor"] = round(achieved, 2)
            if pace > 0:
                out["realTimeFactorTarget"] = pace
                out["realTimeBehind"] = 1.0 if achieved < pace * KEEP_UP_TOLERANCE else 0.0
        return out


def behind_note(metrics: Mapping[str, float]) -> str | None:
    """A log line when a paced run could not keep up, else None."""
    if metrics.get("realTimeBehind") != 1.0:
        return None
    return (
        f"could not keep up: real-time factor {metrics['realTimeFactorTarget']:g} asked, "
        f"{metrics['loopRealTimeFactor']:g} achieved"
    )
