"""Reading per-scenario detail from a run's files.

Covers: trajectories and timelines embedded in a result JSON (both spellings of a timeline,
non-finite values kept as gaps, the ego picked by name or first entity); thinning long series to
the point limit with both ends kept; artifact URIs (relative, absolute, file://, remote); and
that an unreadable result file, a remote or missing recording, or a reader error become notes
while a readable recording supplies the trajectories.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import NamedTuple

from simtest_operator import results
from simtest_operator.errors import ResultsError
from simtest_operator.results import details
from tests.results.resultdata import outcome, scenario


def test_result_file_with_trajectories_and_timelines() -> None:
    parsed = details.parse_result_file(
        {
            "trajectories": {"lead": [[0, 10, 0], [1, 20, 0]], "ego": [[0, 0, 0], [1, 5, 1]]},
            "timelines": {
                "ttc": {"unit": "s", "points": [[0, 3.0], [1, "Infinity"]]},
                "speed": [[0, 20], [1, 21]],
            },
        }
    )
    assert [(t.entity, t.is_ego) for t in parsed.trajectories] == [("lead", False), ("ego", True)]
    assert parsed.trajectories[1].points == ((0.0, 0.0, 0.0), (1.0, 5.0, 1.0))
    assert [(t.name, t.unit) for t in parsed.timelines] == [("speed", ""), ("ttc", "s")]
    assert parsed.timelines[1].points[0] == (0.0, 3.0)
    assert math.isnan(parsed.timelines[1].points[1][1])
    assert details.parse_result_file({"trajectories": {"a": [[0, 1, 2]]}}).trajectories[0].is_ego
    assert details.parse_result_file({"verdict": "Passed"}) == details.ScenarioDetails()


def test_thinning_keeps_both_ends() -> None:
    points = list(range(1001))
    thinned = details.thin(points, 100)
    assert len(thinned) == 100
    assert (thinned[0], thinned[-1]) == (0, 1000)
    assert list(thinned) == sorted(set(thinned))
    assert details.thin(points[:50], 100) == tuple(points[:50])


def test_artifact_paths(tmp_path: Path) -> None:
    assert details.artifact_path("a/rec.mcap", tmp_path) == tmp_path / "a/rec.mcap"
    assert details.artifact_path("/data/rec.mcap", tmp_path) == Path("/data/rec.mcap")
    assert details.artifact_path("file:///data/my%20rec.mcap", tmp_path) == Path(
        "/data/my rec.mcap"
    )
    assert details.artifact_path("s3://bucket/rec.mcap", tmp_path) is None


def _stored(**artifacts: str) -> results.StoredOutcome:
    return results.StoredOutcome(scenario=scenario("a.xosc"),
                                 outcome=outcome("a.xosc", artifacts=artifacts))  # fmt: skip


def test_problems_become_notes(tmp_path: Path) -> None:
    (tmp_path / "bad.json").write_text("{not json", encoding="utf-8")
    (tmp_path / "rec.mcap").write_bytes(b"not an mcap")

    def failing_reader(path: Path) -> list[details.Trajectory]:
        raise ResultsError(f"cannot read recording {path.name}: bad magic")

    loaded = details.load(_stored(result="bad.json", recording="rec.mcap"), tmp_path,
                          read_trajectories=failing_reader)  # fmt: skip
    assert loaded.trajectories == ()
    assert loaded.notes[0].startswith("result file bad.json unreadable")
    assert loaded.notes[1] == "cannot read recording rec.mcap: bad magic"
    remote = details.load(_stored(result="s3://b/r.json", recording="missing.mcap"), tmp_path,
                          read_trajectories=failing_reader)  # fmt: skip
    assert remote.notes == ("result file s3://b/r.json is remote; not read",
                            "recording missing.mcap not found")  # fmt: skip


def test_recording_supplies_trajectories_unless_the_result_file_has_them(tmp_path: Path) -> None:
    (tmp_path / "rec.mcap").write_bytes(b"")
    from_reader = details.Trajectory(entity="ego", points=((0.0, 1.0, 2.0),), is_ego=True)
    calls: list[Path] = []

    def reader(path: Path) -> list[details.Trajectory]:
        calls.append(path)
        return [from_reader]

    (tmp_path / "r.json").write_text(json.dumps({"timelines": {"v": [[0, 1]]}}), encoding="utf-8")
    loaded = details.load(_stored(result="r.json", recording="rec.mcap"), tmp_path,
                          read_trajectories=reader)  # fmt: skip
    assert loaded.trajectories == (from_reader,)
    assert [t.name for t in loaded.timelines] == ["v"]
    assert calls == [tmp_path / "rec.mcap"]
    embedded = {"trajectories": {"ego": [[0, 0, 0]]}}
    (tmp_path / "r.json").write_text(json.dumps(embedded), encoding="utf-8")
    loaded = details.load(_stored(result="r.json", recording="rec.mcap"), tmp_path,
                          read_trajectories=reader)  # fmt: skip
    assert loaded.trajectories[0].points == ((0.0, 0.0, 0.0),)
    assert len(calls) == 1
    assert dataclasses.replace(loaded, notes=()) == loaded


def test_trajectories_from_recording_samples() -> None:
    class Sample(NamedTuple):
        t: float
        x: float
        y: float

    samples = {7: [Sample(0, 5, 5), Sample(1, 6, 5)], 3: [Sample(0, 0, 0), Sample(1, 1, 0)]}
    unnamed = details.from_samples(samples)
    assert [(t.entity, t.is_ego) for t in unnamed] == [("ego", True), ("object 7", False)]
    assert unnamed[1].points == ((0.0, 5.0, 5.0), (1.0, 6.0, 5.0))
    named = details.from_samples(samples, names={"entity.7": "cutter", "entity.3": "hero"})
    assert [(t.entity, t.is_ego) for t in named] == [("hero", True), ("cutter", False)]
    assert details.from_samples({}) == []
