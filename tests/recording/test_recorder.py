"""Recorder end to end, read back with omega-prime (validation on) and with our own reader:
object ids and counts, bounding-box centres (rotated boxes with lateral offsets), yaw within
[-pi, pi], velocity of the box centre (travel and yaw rate), vehicle classification per category,
pedestrians and misc objects, an entity leaving and coming back under a fresh id (no gaps), late
and early-leaving entities, 20 Hz input thinned to 10 Hz, the embedded OpenDRIVE map and its
map_reference, metadata records and channel metadata; the frame layout following order, box and
category changes, random entity churn decoded with betterosi frame by frame against its
snapshots, an unclosed (killed) recording keeping its finished chunks. The write cost per frame
is measured by bench/simulator.py, not here."""

from __future__ import annotations

import dataclasses
import math
import random
import warnings
from pathlib import Path

import pytest
from mcap.exceptions import EndOfFile
from mcap.reader import make_reader
from mcap.records import Message
from mcap.stream_reader import StreamReader

from simtest_operator.errors import ResultsError
from simtest_operator.recording import Recorder, RecordingInfo, read_metadata, read_trajectories
from simtest_operator.recording.objects import read_objects
from simtest_operator.recording.writing import DISCONTINUITY_METADATA
from simtest_operator.snapshots import (
    BoundingBox,
    Discontinuity,
    EntityKind,
    EntityState,
    JumpCause,
    WorldSnapshot,
)

XODR = (
    Path(__file__).resolve().parents[3]
    / "shared" / "scenarios-dev" / "esmini" / "resources" / "xodr" / "straight_500m.xodr"
)  # fmt: skip
CAR_BOX = BoundingBox(center_x=1.4, center_y=0.2, center_z=0.75, length=4.5, width=1.8, height=1.5)
PERSON_BOX = BoundingBox(center_z=0.9, length=0.5, width=0.6, height=1.8)
CONE_BOX = BoundingBox(center_z=0.3, length=0.4, width=0.4, height=0.6)
CATEGORIES = {0: "car", 1: "truck", 2: "bus", 3: "bicycle", 4: "motorbike"}


def world(t: float) -> WorldSnapshot:
    """Five vehicles (ego 0), a pedestrian from t=1 s, a cone until t=3 s, and vehicle 4 missing
    between t=2 s and t=3 s."""
    entities = []
    for entity_id, category in CATEGORIES.items():
        if entity_id == 4 and 2.0 <= t < 3.0:
            continue
        entities.append(
            EntityState(
                id=entity_id, name=f"v{entity_id}", kind=EntityKind.VEHICLE, category=category,
                x=20.0 * entity_id + 15.0 * t, y=-1.5, heading=3.5 if entity_id == 2 else 0.2,
                speed=15.0, travel=(14.5, 3.0), yaw_rate=0.25, acceleration=-1.0, box=CAR_BOX,
            )
        )  # fmt: skip
    if t >= 1.0:
        entities.append(
            EntityState(
                id=10, name="walker", kind=EntityKind.PEDESTRIAN, category="pedestrian",
                x=60.0, y=-8.0 + t, heading=math.pi / 2, speed=1.0, box=PERSON_BOX,
            )
        )  # fmt: skip
    if t < 3.0:
        entities.append(
            EntityState(
                id=11, name="cone", kind=EntityKind.MISC_OBJECT, category="obstacle",
                x=100.0, y=-1.5, box=CONE_BOX,
            )
        )  # fmt: skip
    return WorldSnapshot(time=t, entities=tuple(entities))


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("rec") / "run.mcap"
    info = RecordingInfo(scenario_id="cut-in-7", seed=42, versions={"sumo": "1.28.0"})
    with Recorder(
        path, info=info, opendrive=XODR.read_bytes(), map_reference="straight_500m",
        host_id=0, period=0.1,
    ) as recorder:  # fmt: skip
        for step in range(101):  # 5 s at 20 Hz
            recorder.write(world(round(step * 0.05, 10)))
        assert recorder.frames == 51
    return path


@pytest.fixture(scope="module")
def omega(recording: Path):  # type: ignore[no-untyped-def]
    with warnings.catch_warnings():
        # omega-prime 0.3.7 still uses betterosi's deprecated class names.
        warnings.simplefilter("ignore", DeprecationWarning)
        import omega_prime

        return omega_prime.Recording.from_file(
            str(recording), validate=True, parse_map=True, apply_proj=False
        )


def test_omega_prime_validates_and_sees_every_object(omega) -> None:  # type: ignore[no-untyped-def]
    df = omega.df
    assert omega.host_vehicle_idx == 0
    assert omega.map is not None
    counts = dict(df.group_by("idx").len().sort("idx").iter_rows())
    reissued = [idx for idx in counts if idx >= 1_000_000_000]
    assert len(reissued) == 1
    assert counts == {0: 51, 1: 51, 2: 51, 3: 51, 4: 20, 10: 41, 11: 30, reissued[0]: 21}
    assert df["total_nanos"].n_unique() == 51
    assert df["total_nanos"].max() == 5_000_000_000
    types = dict(df.select("idx", "type").unique().iter_rows())
    assert types[0] == 2 and types[10] == 3 and types[11] == 1
    subtypes = dict(df.filter(df["type"] == 2).select("idx", "subtype").unique().iter_rows())
    assert (subtypes[0], subtypes[1], subtypes[2], subtypes[3], subtypes[4]) == (4, 7, 13, 12, 11)


def test_positions_are_box_centres(omega) -> None:  # type: ignore[no-untyped-def]
    row = omega.df.filter((omega.df["idx"] == 2) & (omega.df["total_nanos"] == 1_500_000_000))
    state = world(1.5).entity("v2")
    assert state is not None
    cx, cy, cz = state.box_center()
    vx, vy = state.box_velocity()
    assert row["x"][0] == pytest.approx(cx)
    assert row["y"][0] == pytest.approx(cy)
    assert row["z"][0] == pytest.approx(cz)
    assert row["vel_x"][0] == pytest.approx(vx)
    assert row["vel_y"][0] == pytest.approx(vy)
    assert row["yaw"][0] == pytest.approx(3.5 - 2 * math.pi)
    assert row["acc_x"][0] == pytest.approx(-math.cos(3.5))
    assert (row["length"][0], row["width"][0], row["height"][0]) == (4.5, 1.8, 1.5)


def test_own_reader_matches(recording: Path) -> None:
    trajectories = read_trajectories(recording)
    assert sorted(trajectories)[:7] == [0, 1, 2, 3, 4, 10, 11]
    assert len(trajectories[0]) == 51
    sample = trajectories[10][0]
    assert sample.t == pytest.approx(1.0)
    assert (sample.x, sample.y) == pytest.approx((60.0, -7.0))
    assert sample.heading == pytest.approx(math.pi / 2)
    assert sample.speed == pytest.approx(1.0)
    times = [sample.t for sample in trajectories[4]]
    assert times[-1] == pytest.approx(1.9)


def test_metadata_map_and_channels(recording: Path) -> None:
    metadata = read_metadata(recording)
    trace = metadata["net.asam.osi.trace"]
    assert trace["version"] == "3.7.0"
    assert {"min_osi_version", "max_osi_version", "min_protobuf_version"} <= set(trace)
    assert metadata["simtest.run"] == {
        "scenario_id": "cut-in-7",
        "seed": "42",
        "version.sumo": "1.28.0",
    }
    with recording.open("rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    channels = {channel.topic: channel for channel in summary.channels.values()}
    assert set(channels) == {"ground_truth", "ground_truth_map"}
    for channel in channels.values():
        assert channel.metadata["net.asam.osi.trace.channel.osi_version"] == "3.7.0"
    schemas = {summary.schemas[c.schema_id].name for c in channels.values()}
    assert schemas == {"osi3.GroundTruth", "osi3.MapAsamOpenDrive"}
    assert recording.stat().st_size < 400_000


def test_map_reference_matches(recording: Path) -> None:
    import betterosi

    osi = betterosi.v3_7_0
    with recording.open("rb") as stream:
        messages = {
            channel.topic: message.data
            for _, channel, message in make_reader(stream).iter_messages()
        }
    road = osi.MapAsamOpenDrive.from_binary(messages["ground_truth_map"])
    last = osi.GroundTruth.from_binary(messages["ground_truth"])
    assert road.map_reference == last.map_reference == "straight_500m"
    assert road.open_drive_xml_content == XODR.read_text()


def test_frame_layout_follows_order_box_and_category_changes(tmp_path: Path) -> None:
    """The cached frame layout is rebuilt whenever the order, a box or a category changes (equal
    new box objects keep it); every frame decodes to its own snapshot's values."""
    import betterosi

    osi = betterosi.v3_7_0
    long_box = BoundingBox(center_x=2.0, center_y=-0.3, center_z=1.0, length=9.0, width=2.5)

    def state(entity_id: int, k: int, **changes: object) -> EntityState:
        base = EntityState(
            id=entity_id, name=f"e{entity_id}", kind=EntityKind.VEHICLE, category="car",
            x=5.0 * k + entity_id, y=float(entity_id), heading=0.3 * k, pitch=4.0, roll=-0.1,
            speed=10.0 + k, yaw_rate=3.0, acceleration=1.5, box=CAR_BOX,
        )  # fmt: skip
        return dataclasses.replace(base, **changes)  # type: ignore[arg-type]

    snapshots = [
        WorldSnapshot(time=0.0, entities=(state(0, 0), state(1, 0), state(2, 0))),
        WorldSnapshot(time=0.1, entities=(state(0, 1), state(1, 1), state(2, 1))),
        WorldSnapshot(time=0.2, entities=(state(2, 2), state(0, 2), state(1, 2))),
        WorldSnapshot(
            time=0.3,
            entities=(state(2, 3), state(0, 3, box=dataclasses.replace(CAR_BOX)), state(1, 3)),
        ),
        WorldSnapshot(time=0.4, entities=(state(2, 4), state(0, 4, box=long_box), state(1, 4))),
        WorldSnapshot(
            time=0.5,
            entities=(state(2, 5), state(0, 5, box=long_box), state(1, 5, category="bus")),
        ),
    ]
    path = tmp_path / "changes.mcap"
    with Recorder(path, info=RecordingInfo(scenario_id="s", seed=0), host_id=1) as recorder:
        for snapshot in snapshots:
            assert recorder.write(snapshot)
    with path.open("rb") as stream:
        frames = [
            osi.GroundTruth.from_binary(message.data)
            for _, _, message in make_reader(stream).iter_messages(topics=["ground_truth"])
        ]
    assert len(frames) == len(snapshots)
    for frame, snapshot in zip(frames, snapshots, strict=True):
        assert frame.host_vehicle_id.value == 1
        assert [obj.id.value for obj in frame.moving_object] == [e.id for e in snapshot.entities]
        for obj, expected in zip(frame.moving_object, snapshot.entities, strict=True):
            base = obj.base
            assert (base.position.x, base.position.y, base.position.z) == pytest.approx(
                expected.box_center()
            )
            assert (base.velocity.x, base.velocity.y) == pytest.approx(expected.box_velocity())
            assert base.orientation.yaw == pytest.approx(math.remainder(expected.heading, math.tau))
            assert base.orientation.pitch == pytest.approx(4.0 - math.tau)
            assert base.orientation.roll == -0.1
            dimension = (base.dimension.length, base.dimension.width, base.dimension.height)
            assert dimension == (expected.box.length, expected.box.width, expected.box.height)
            expected_class = 13 if expected.category == "bus" else 4
            assert obj.vehicle_classification.type == expected_class


def random_state(rng: random.Random, entity_id: int) -> EntityState:
    boxes = (CAR_BOX, PERSON_BOX, CONE_BOX, BoundingBox(length=0.0, width=0.0, height=0.0))
    return EntityState(
        id=entity_id, name=f"e{entity_id}", kind=rng.choice(list(EntityKind)),
        category=rng.choice(("car", "truck", "animal", "obstacle")),
        x=rng.uniform(-1e4, 1e4), y=rng.uniform(-1e3, 1e3), z=rng.uniform(-5.0, 5.0),
        heading=rng.uniform(-20.0, 20.0), pitch=rng.choice((0.0, math.pi, 4.0)),
        roll=rng.uniform(-7.0, 7.0), speed=rng.uniform(-5.0, 50.0),
        acceleration=rng.uniform(-9.0, 3.0), yaw_rate=rng.uniform(-1.0, 1.0),
        travel=rng.choice((None, (rng.uniform(-5.0, 50.0), rng.uniform(-5.0, 5.0)))),
        box=rng.choice(boxes),
    )  # fmt: skip


def test_random_churn_decodes_to_every_snapshot(tmp_path: Path) -> None:
    """Entities appearing, leaving, coming back and changing order, box, kind and category at
    random, with angles far outside [-pi, pi]: each frame decodes with betterosi to its own
    snapshot, and ids follow the no-gaps rule (a returning entity gets a fresh id)."""
    import betterosi

    osi = betterosi.v3_7_0
    rng = random.Random(7)
    snapshots = [
        WorldSnapshot(
            time=k * 0.1,
            entities=tuple(
                random_state(rng, entity_id)
                for entity_id in rng.sample(range(0, 300, 25), rng.randint(0, 12))
            ),
        )
        for k in range(120)
    ]
    path = tmp_path / "churn.mcap"
    with Recorder(path, info=RecordingInfo(scenario_id="s", seed=0)) as recorder:
        for snapshot in snapshots:
            recorder.write(snapshot)
    with path.open("rb") as stream:
        frames = [
            osi.GroundTruth.from_binary(message.data)
            for _, _, message in make_reader(stream).iter_messages(topics=["ground_truth"])
        ]
    assert len(frames) == len(snapshots)
    ids: dict[int, int] = {}
    previous: set[int] = set()
    reissued = 0
    for frame, snapshot in zip(frames, snapshots, strict=True):
        assert len(frame.moving_object) == len(snapshot.entities)
        for obj, state in zip(frame.moving_object, snapshot.entities, strict=True):
            if state.id in ids and state.id not in previous:  # back after a gap
                reissued += 1
                assert obj.id.value >= 1_000_000_000
                assert obj.id.value not in ids.values()
            else:
                assert obj.id.value == ids.get(state.id, state.id)
            ids[state.id] = obj.id.value
            base = obj.base
            position = (base.position.x, base.position.y, base.position.z)
            assert position == pytest.approx(state.box_center(), abs=1e-9)
            assert (base.velocity.x, base.velocity.y) == pytest.approx(state.box_velocity())
            orientation = (base.orientation.roll, base.orientation.pitch, base.orientation.yaw)
            assert all(-math.pi <= angle <= math.pi for angle in orientation)
            angles = (state.roll, state.pitch, state.heading)
            assert orientation == pytest.approx([math.remainder(a, math.tau) for a in angles])
            assert base.dimension.length == max(state.box.length, 0.01)
            animal = state.kind is EntityKind.PEDESTRIAN and state.category == "animal"
            kinds = {EntityKind.VEHICLE: 2, EntityKind.PEDESTRIAN: 3, EntityKind.MISC_OBJECT: 1}
            assert obj.type == (4 if animal else kinds[state.kind])
        previous = {state.id for state in snapshot.entities}
    assert reissued > 10


def test_unclosed_recording_keeps_its_finished_chunks(tmp_path: Path) -> None:
    """A run killed before ``close`` leaves every chunk finished so far readable by a streaming
    reader (chunks are written as they fill; nothing is held back for later)."""
    path = tmp_path / "killed.mcap"
    recorder = Recorder(path, info=RecordingInfo(scenario_id="s", seed=0), opendrive="<OpenDRIVE/>")
    for k in range(1500):  # about 1.9 MB of GroundTruth: at least one finished 1 MiB chunk
        recorder.write(world(k * 0.05))
    read: list[float] = []
    with path.open("rb") as stream, pytest.raises(EndOfFile):
        for record in StreamReader(stream).records:
            if isinstance(record, Message):
                read.append(record.log_time * 1e-9)
    recorder.close()
    assert len(read) > 300
    assert read == sorted(read)
    assert len(read_trajectories(path)[0]) == recorder.frames


def test_force_and_closed_recorder(tmp_path: Path) -> None:
    path = tmp_path / "short.mcap"
    recorder = Recorder(path, info=RecordingInfo(scenario_id="s", seed=0), period=1.0)
    assert recorder.write(world(0.0))
    assert not recorder.write(world(0.5))
    assert recorder.write(world(0.7), force=True)
    assert not recorder.write(world(0.7), force=True)
    recorder.close()
    recorder.close()
    with pytest.raises(ResultsError, match="closed"):
        recorder.write(world(2.0))
    assert [sample.t for sample in read_trajectories(path)[0]] == pytest.approx([0.0, 0.7])


def test_empty_recording_still_has_the_map(tmp_path: Path) -> None:
    path = tmp_path / "empty.mcap"
    with Recorder(path, info=RecordingInfo(scenario_id="s", seed=0), opendrive="<OpenDRIVE/>"):
        pass
    with path.open("rb") as stream:
        topics = [channel.topic for _, channel, _ in make_reader(stream).iter_messages()]
    assert topics == ["ground_truth_map"]
    assert read_trajectories(path) == {}


def test_declared_jumps_are_recorded_with_the_osi_id_the_entity_had_then(tmp_path: Path) -> None:
    # Vehicle 4 is deleted at t=2 s and added again at t=3 s under a fresh OSI id: its
    # deletion names the id it had, its return the id it has from then on.
    path = tmp_path / "jumps.mcap"
    with Recorder(path, info=RecordingInfo(scenario_id="j", seed=1), period=0.1) as recorder:
        for step in range(101):
            recorder.write(world(round(step * 0.05, 10)))
        for time, cause in ((2.0, JumpCause.DELETED), (3.0, JumpCause.ADDED)):
            recorder.add_discontinuity(Discontinuity(time=time, entity=4, cause=cause))
        recorder.add_discontinuity(Discontinuity(time=1.5, entity=0, cause=JumpCause.TELEPORT))
    decoded = read_objects(path)
    (fresh,) = [i for i in decoded.objects if i >= 1_000_000_000]
    assert decoded.objects[fresh].t[0] == 3.0
    assert decoded.discontinuities == (
        Discontinuity(time=2.0, entity=4, cause=JumpCause.DELETED, object_id=4),
        Discontinuity(time=3.0, entity=4, cause=JumpCause.ADDED, object_id=fresh),
        Discontinuity(time=1.5, entity=0, cause=JumpCause.TELEPORT, object_id=0),
    )


def test_a_malformed_jump_record_makes_the_recording_unreadable(tmp_path: Path) -> None:
    path = tmp_path / "bad.mcap"
    with Recorder(path, info=RecordingInfo(scenario_id="j", seed=1), period=0.1) as recorder:
        recorder.write(world(0.0))
        recorder._writer.add_metadata(DISCONTINUITY_METADATA, {"time": "1", "cause": "warp"})
    with pytest.raises(ResultsError, match="cannot read recording"):
        read_objects(path)
