"""Per-scenario detail for the developer view: trajectories, metric timelines, notes.

The store keeps verdicts and key metrics; what a developer needs to understand a failure lives in
the run's files. This module defines the values the report plots and reads them from the two
places they can come from:

* the recording (omega-prime MCAP), through a reader the caller passes in (the CLI wires
  :func:`simtest_operator.recording.read_trajectories`; ``results`` does not import
  ``recording``, both sit on the same layer);
* the full result JSON next to the artifacts, which may carry ``"trajectories"``
  (``{entity: [[t, x, y], ...]}``) and ``"timelines"`` (``{name: [[t, value], ...]}`` or
  ``{name: {"unit": "s", "points": [[t, value], ...]}}``).

Artifact URIs are paths relative to the output folder, absolute paths or ``file://`` URIs; other
schemes (``s3://``) are listed in the report but not opened.
"""

from __future__ import annotations

import dataclasses
import json
import math
import urllib.parse
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, Protocol

from simtest_operator.errors import ResultsError, SimtestError
from simtest_operator.results import records

MAX_POINTS = 400
"""Points kept per plotted line; longer series are thinned evenly (the ends always kept)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Trajectory:
    """Where one entity went: (t, x, y) in the map frame, in time order."""

    entity: str
    points: tuple[tuple[float, float, float], ...]
    is_ego: bool = False


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Timeline:
    """One metric over simulated time: (t, value)."""

    name: str
    points: tuple[tuple[float, float], ...]
    unit: str = ""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ScenarioDetails:
    """Everything the developer view shows beyond the stored outcome."""

    trajectories: tuple[Trajectory, ...] = ()
    timelines: tuple[Timeline, ...] = ()
    notes: tuple[str, ...] = ()
    """Why something is missing (unreadable recording, remote artifact, plot limit)."""


TrajectoryReader = Callable[[Path], Sequence[Trajectory]]
"""Reads a recording into trajectories; raises a :class:`SimtestError` if it cannot."""


class Sample(Protocol):
    """What a recording reader yields per object and instant (``recording.Sample`` fits)."""

    @property
    def t(self) -> float: ...

    @property
    def x(self) -> float: ...

    @property
    def y(self) -> float: ...


def from_samples(
    samples: Mapping[int, Sequence[Sample]], *, names: Mapping[str, str] | None = None
) -> list[Trajectory]:
    """Trajectories from a recording reader's ``{object id: samples}``.

    Objects are named from ``entity.<id>`` keys of ``names`` (the recording's ``simtest.run``
    metadata) when present, else ``ego`` / ``object <id>``; the ego is the OSI host vehicle, by
    the recorder's convention the smallest id. Wire it up as::

        lambda path: details.from_samples(recording.read_trajectories(path),
                                          names=recording.read_metadata(path).get("simtest.run"))
    """
    ego = min(samples, default=None)
    names = names or {}
    return [
        Trajectory(
            entity=names.get(
                f"entity.{object_id}", "ego" if object_id == ego else f"object {object_id}"
            ),
            points=thin([(s.t, s.x, s.y) for s in track]),
            is_ego=object_id == ego,
        )
        for object_id, track in sorted(samples.items())
    ]


def thin(points: Sequence[Any], limit: int = MAX_POINTS) -> tuple[Any, ...]:
    """At most ``limit`` evenly spaced items of ``points``, first and last included."""
    if len(points) <= limit:
        return tuple(points)
    step = (len(points) - 1) / (limit - 1)
    return tuple(points[round(i * step)] for i in range(limit))


def artifact_path(uri: str, base: Path) -> Path | None:
    """The local file an artifact URI names, or ``None`` for a remote one."""
    parsed = urllib.parse.urlparse(uri)
    if parsed.scheme == "file":
        return Path(urllib.parse.unquote(parsed.path))
    if parsed.scheme and len(parsed.scheme) > 1:  # "C:" stays a path
        return None
    path = Path(uri)
    return path if path.is_absolute() else base / path


def parse_result_file(document: Mapping[str, Any]) -> ScenarioDetails:
    """Trajectories and timelines embedded in a full result JSON (both optional)."""
    trajectories = []
    raw_trajectories = document.get("trajectories") or {}
    if not isinstance(raw_trajectories, Mapping):
        raise ResultsError("'trajectories' must map entity names to [[t, x, y], ...]")
    for index, (entity, points) in enumerate(raw_trajectories.items()):
        trajectories.append(
            Trajectory(
                entity=str(entity),
                points=thin([(float(t), float(x), float(y)) for t, x, y in points]),
                is_ego=str(entity) == "ego" or (index == 0 and "ego" not in raw_trajectories),
            )
        )
    timelines = []
    raw_timelines = document.get("timelines") or {}
    if not isinstance(raw_timelines, Mapping):
        raise ResultsError("'timelines' must map metric names to [[t, value], ...]")
    for name, series in sorted(raw_timelines.items()):
        unit = ""
        if isinstance(series, Mapping):
            unit = str(series.get("unit", ""))
            series = series.get("points", [])
        timelines.append(
            Timeline(
                name=str(name),
                unit=unit,
                points=thin([(float(t), _finite(v)) for t, v in series]),
            )
        )
    return ScenarioDetails(trajectories=tuple(trajectories), timelines=tuple(timelines))


def load(
    stored: records.StoredOutcome,
    base: Path,
    *,
    read_trajectories: TrajectoryReader | None = None,
) -> ScenarioDetails:
    """Read the detail of one scenario from its artifacts; problems become notes, not errors."""
    notes: list[str] = []
    trajectories: tuple[Trajectory, ...] = ()
    timelines: tuple[Timeline, ...] = ()
    artifacts = stored.outcome.artifacts
    result_uri = artifacts.get("result")
    if result_uri:
        path = artifact_path(result_uri, base)
        if path is None:
            notes.append(f"result file {result_uri} is remote; not read")
        elif path.is_file():
            try:
                embedded = parse_result_file(json.loads(path.read_text(encoding="utf-8")))
            except (OSError, ValueError, TypeError, SimtestError) as exc:
                notes.append(f"result file {result_uri} unreadable: {exc}")
            else:
                trajectories, timelines = embedded.trajectories, embedded.timelines
    recording_uri = artifacts.get("recording")
    if recording_uri and read_trajectories is not None and not trajectories:
        path = artifact_path(recording_uri, base)
        if path is None:
            notes.append(f"recording {recording_uri} is remote; not read")
        elif not path.is_file():
            notes.append(f"recording {recording_uri} not found")
        else:
            try:
                trajectories = tuple(read_trajectories(path))
            except SimtestError as exc:
                notes.append(str(exc))
    return ScenarioDetails(trajectories=trajectories, timelines=timelines, notes=tuple(notes))


def _finite(value: Any) -> float:
    number = float(value)
    return number if math.isfinite(number) else math.nan
