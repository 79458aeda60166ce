"""Base-scenario decomposition: synthetic scenes with exact answers, then real recordings of the
generated library whose base scenarios are known by construction of each template."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from simtest_operator.evaluation.basescenarios import Kind, decompose
from simtest_operator.evaluation.scenes import ActorKind, Scene, Track, scene_from_columns
from simtest_operator.recording.objects import read_objects
from tests.evaluation import recorded_runs

pytestmark = pytest.mark.timeout(300)

T = np.round(np.arange(0.0, 20.0 + 1e-9, 0.1), 6)


def track(
    object_id: int,
    x: np.ndarray,
    y: np.ndarray,
    *,
    kind: ActorKind = ActorKind.VEHICLE,
    length: float = 4.5,
    width: float = 1.8,
) -> Track:
    vx, vy = np.gradient(x, T), np.gradient(y, T)
    yaw = np.arctan2(vy, vx)
    return Track(
        object_id=object_id, kind=kind, length=length, width=width, t=T, x=x, y=y, yaw=yaw,
        vx=vx, vy=vy, ax=np.gradient(vx, T), ay=np.gradient(vy, T),
    )  # fmt: skip


def scene(*others: Track, ego_speed: float = 25.0) -> Scene:
    ego = track(0, ego_speed * T, np.zeros_like(T))
    return Scene(ego=ego, others=others, frame_times=T)


def kinds(s: Scene) -> dict[Kind, list[tuple[float, float, int | None]]]:
    found: dict[Kind, list[tuple[float, float, int | None]]] = {}
    for b in decompose(s).base_scenarios:
        found.setdefault(b.kind, []).append((b.start, b.end, b.actor))
    return found


def test_an_empty_road_is_free_driving_over_the_whole_run() -> None:
    found = kinds(scene())
    assert list(found) == [Kind.FREE_DRIVING]
    assert found[Kind.FREE_DRIVING] == [(0.0, 20.0, None)]


def test_a_lead_at_constant_gap_is_following_only() -> None:
    lead = track(1, 25.0 * T + 40.0, np.zeros_like(T))
    assert list(kinds(scene(lead))) == [Kind.FOLLOWING]


def test_a_slower_lead_is_approached_then_followed_after_the_ego_adapts() -> None:
    # The ego closes at 5 m/s for 8 s, then matches the lead's speed.
    ego_x = np.where(T < 8.0, 25.0 * T, 200.0 + 20.0 * (T - 8.0))
    lead = track(1, 20.0 * T + 80.0, np.zeros_like(T))
    s = Scene(ego=track(0, ego_x, np.zeros_like(T)), others=(lead,), frame_times=T)
    found = kinds(s)
    (approach,) = found[Kind.APPROACHING]
    assert approach[0] == 0.0 and 7.5 <= approach[1] <= 8.1
    assert any(start >= 7.9 for start, _, _ in found[Kind.FOLLOWING])


def test_a_cut_in_from_the_left_is_found_at_its_time_with_its_actor() -> None:
    # Adjacent lane (3.5 m left) until t=5, moves in over 2 s, 30 m ahead at the ego's speed.
    lateral = np.interp(T, [0.0, 5.0, 7.0, 20.0], [3.5, 3.5, 0.0, 0.0])
    cutter = track(7, 25.0 * T + 30.0, lateral)
    found = kinds(scene(cutter))
    (cut_in,) = found[Kind.CUT_IN]
    # The centre crosses half a lane at t=6 s; the window is 2 s before to 3 s after.
    assert cut_in == (pytest.approx(4.0, abs=0.11), pytest.approx(9.0, abs=0.11), 7)
    assert Kind.CUT_OUT not in found and Kind.CROSSING not in found
    assert any(start <= 6.1 for start, _, _ in found[Kind.FOLLOWING])


def test_a_lead_that_leaves_the_lane_is_a_cut_out() -> None:
    lateral = np.interp(T, [0.0, 8.0, 10.0, 20.0], [0.0, 0.0, -3.5, -3.5])
    leaver = track(3, 25.0 * T + 30.0, lateral)
    found = kinds(scene(leaver))
    ((start, end, actor),) = found[Kind.CUT_OUT]
    assert actor == 3 and start == pytest.approx(7.0, abs=0.11) and end <= 12.01
    assert Kind.CUT_IN not in found


def test_a_car_crossing_the_path_at_right_angles_is_a_crossing() -> None:
    # Crosses the ego's path at x=250 (reached by the ego at t=10) at t=11, 10 m/s northwards.
    crosser = track(5, np.full_like(T, 250.0), 10.0 * (T - 11.0))
    found = kinds(scene(crosser))
    assert [actor for _, _, actor in found[Kind.CROSSING]] == [5]
    assert Kind.VRU not in found


def test_a_pedestrian_crossing_is_a_vru_interaction_not_a_crossing() -> None:
    walker = track(
        9, np.full_like(T, 250.0), 1.4 * (T - 10.0), kind=ActorKind.PEDESTRIAN, length=0.5,
        width=0.5,
    )  # fmt: skip
    found = kinds(scene(walker))
    assert [actor for _, _, actor in found[Kind.VRU]] == [9]
    assert Kind.CROSSING not in found


def test_oncoming_traffic_in_its_own_lane_is_no_interaction() -> None:
    oncoming = track(2, 600.0 - 25.0 * T, np.full_like(T, 3.5))
    assert list(kinds(scene(oncoming))) == [Kind.FREE_DRIVING]


def test_a_single_frame_has_no_base_scenarios() -> None:
    first = slice(0, 1)
    one = Track(
        object_id=0, kind=ActorKind.VEHICLE, length=4.5, width=1.8, t=T[first],
        x=T[first], y=T[first], yaw=T[first], vx=T[first], vy=T[first], ax=T[first],
        ay=T[first],
    )  # fmt: skip
    other = dataclasses.replace(one, object_id=1, x=one.x + 20.0)
    decomposition = decompose(Scene(ego=one, others=(other,), frame_times=T[first]))
    assert decomposition.base_scenarios == ()


# --- the generated library, known by construction --------------------------------------------

EXPECTED: dict[str, tuple[set[Kind], set[Kind]]] = {
    # category: (must all be found, must not be found)
    "following": ({Kind.FOLLOWING}, {Kind.CUT_IN, Kind.CUT_OUT, Kind.CROSSING, Kind.VRU}),
    "hard-braking": (
        {Kind.FOLLOWING, Kind.APPROACHING},
        {Kind.CUT_IN, Kind.CUT_OUT, Kind.CROSSING, Kind.VRU},
    ),
    "cut-in": ({Kind.CUT_IN}, {Kind.CUT_OUT, Kind.CROSSING, Kind.VRU}),
    "cut-out": ({Kind.CUT_OUT, Kind.APPROACHING}, {Kind.CUT_IN, Kind.CROSSING, Kind.VRU}),
    "lane-change": ({Kind.CUT_IN}, {Kind.CUT_OUT, Kind.CROSSING, Kind.VRU}),
    "merge": ({Kind.CUT_IN}, {Kind.CUT_OUT, Kind.CROSSING, Kind.VRU}),
    "ltap": ({Kind.CROSSING}, {Kind.CUT_IN, Kind.CUT_OUT, Kind.VRU, Kind.FOLLOWING}),
    "pedestrian-crossing": ({Kind.VRU}, {Kind.CUT_IN, Kind.CUT_OUT, Kind.CROSSING}),
}
SIDE = {"cut-in": "from the right", "lane-change": "from the left", "merge": "from the right"}


@pytest.fixture(scope="module")
def library_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("library")
    include = [name for category in EXPECTED for name in recorded_runs.sample(category)]
    manifest = recorded_runs.write_manifest(
        folder, name="known", source=recorded_runs.LIBRARY, include=include
    )
    return recorded_runs.run_campaign(manifest, folder / "out")


def test_library_recordings_decompose_into_their_templates_base_scenarios(
    library_run: Path,
) -> None:
    recordings = sorted((library_run / "scenarios").glob("*/recording.mcap"))
    assert len(recordings) == 3 * len(EXPECTED)
    for path in recordings:
        category = path.parent.name.split("__")[0]
        s = scene_from_columns(read_objects(path))
        assert s is not None, path
        bases = decompose(s).base_scenarios
        found = {b.kind for b in bases}
        must, must_not = EXPECTED[category]
        assert must <= found, (path.parent.name, sorted(found))
        assert not (must_not & found), (path.parent.name, sorted(found))
        if category in SIDE:
            cut_ins = [b for b in bases if b.kind is Kind.CUT_IN]
            assert {b.detail for b in cut_ins} == {SIDE[category]}, path.parent.name
            assert {b.actor for b in cut_ins} <= {o.object_id for o in s.others}
        for b in bases:
            assert 0.0 <= b.start <= b.end <= s.ego.t[-1] + 1e-9
            assert s.ego.t[b.first] == b.start and s.ego.t[b.last] == b.end
        assert all(math.isfinite(b.start) for b in bases)


def test_pet_is_omega_primes_timegap(library_run: Path) -> None:
    """Crossing and VRU PET equals omega-prime's min timegap (|t_obj - t_ego| of overlapping
    box polygons); omega-prime looks only 2 s either way, so beyond that it reports none."""
    import warnings

    omega_prime = pytest.importorskip("omega_prime")
    from omega_prime.metrics import MetricManager
    from omega_prime.metrics.analysis import distance_traveled, timegaps_and_min_timegaps, vel

    from simtest_operator.evaluation import quality, reevaluating
    from simtest_operator.verdicts import Verdict

    recordings = sorted((library_run / "scenarios").glob("*/recording.mcap"))
    checked = 0
    for path in recordings:
        if not path.parent.name.startswith(("ltap", "pedestrian-crossing")):
            continue
        decoded = read_objects(path)
        result = reevaluating.evaluate(
            scene_from_columns(decoded),
            quality.assess(decoded, simulated_seconds=0.0),
            reevaluating.DEFAULT_CRITERIA,
            original=Verdict.PASSED,
        )
        (ours,) = [s.metrics["PET"] for s in result.base_scenarios if "PET" in s.metrics]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            recording = omega_prime.Recording.from_file(
                str(path), validate=False, parse_map=False, apply_proj=False
            )
            manager = MetricManager(metrics=[vel, distance_traveled, timegaps_and_min_timegaps])
            _, properties = manager.compute(recording, ego_id=0)
        rows = properties["min_timegaps"]
        rows = rows.collect() if hasattr(rows, "collect") else rows
        theirs = [abs(row["min_timegap"]) for row in rows.to_dicts()]
        if theirs:
            assert ours == pytest.approx(min(theirs), abs=1e-6), path.parent.name
        else:
            assert ours > 2.0, path.parent.name
        checked += 1
    assert checked == 6
