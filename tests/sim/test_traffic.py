"""TrafficActions on SUMO: a swarm keeps its count in the ring around a moving ego, a source
inserts at its rate, a sink removes traffic but never scenario entities, a stop action ends a
source, the same seed gives identical traffic (another seed different traffic), traffic ids are
never reused and have no gaps, the in-memory backend and open space make traffic Invalid, and the
corpus scenario swarm.xosc now runs with the ego matching the reference player."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from simtest_operator.errors import UnsupportedFeatureError
from simtest_operator.evaluation import reference as references
from simtest_operator.runner import scenario_execution
from simtest_operator.sim import BackendChoice, SutConfig, Takeover
from simtest_operator.snapshots import WorldSnapshot
from simtest_operator.verdicts import Verdict
from tests.sim.traffic_scenarios import (
    CORPUS,
    E6MINI,
    STRAIGHT,
    run,
    traffic_event,
    traffic_of,
    write,
)

SWARM = """<TrafficAction trafficName="swarm"><TrafficSwarmAction innerRadius="40"
semiMajorAxis="150" semiMinorAxis="60" offset="0" numberOfVehicles="{count}">
<CentralObject entityRef="Ego"/>
<TrafficDefinition name="mix"><VehicleCategoryDistribution>
<VehicleCategoryDistributionEntry category="car" weight="3"/>
<VehicleCategoryDistributionEntry category="truck" weight="1"/>
</VehicleCategoryDistribution><ControllerDistribution><ControllerDistributionEntry weight="1">
<Controller name="default"><Properties/></Controller></ControllerDistributionEntry>
</ControllerDistribution></TrafficDefinition>
<SpeedRange lowerLimit="10" upperLimit="15"/>
</TrafficSwarmAction></TrafficAction>"""

SOURCE = """<TrafficAction trafficName="{name}"><TrafficSourceAction radius="3" rate="{rate}"
velocity="15"><Position><LanePosition roadId="1" laneId="-1" offset="0" s="{s}"/></Position>
<TrafficDefinition name="cars"><VehicleCategoryDistribution>
<VehicleCategoryDistributionEntry category="car" weight="1"/></VehicleCategoryDistribution>
<ControllerDistribution><ControllerDistributionEntry weight="1"><Controller name="c">
<Properties/></Controller></ControllerDistributionEntry></ControllerDistribution>
</TrafficDefinition></TrafficSourceAction></TrafficAction>"""

SINK = """<TrafficAction><TrafficSinkAction radius="{radius}"><Position>
<LanePosition roadId="1" laneId="-1" offset="0" s="{s}"/></Position></TrafficSinkAction>
</TrafficAction>"""


@pytest.fixture(scope="module")
def nets(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("nets")


def _ellipse(ego_x: float, ego_y: float, heading: float, x: float, y: float) -> float:
    """Normalised ellipse radius of (x, y) for the swarm above (1 on the outer ellipse)."""
    dx, dy = x - ego_x, y - ego_y
    u = dx * math.cos(heading) + dy * math.sin(heading)
    v = -dx * math.sin(heading) + dy * math.cos(heading)
    return math.hypot(u / 150.0, v / 60.0)


def _swarm_run(tmp_path: Path, nets: Path, *, seed: int, end: float = 20.0) -> list[WorldSnapshot]:
    path = write(
        tmp_path,
        road=E6MINI,
        entities={"Ego": ("0", -3, 300.0, 25.0)},
        init_traffic=SWARM.format(count=12),
        end=end,
    )
    return run(path, nets, seed=seed)


def test_swarm_keeps_its_count_in_the_ring_around_a_moving_ego(tmp_path: Path, nets: Path) -> None:
    snapshots = _swarm_run(tmp_path, nets, seed=7)
    counts = [len(traffic_of(s)) for s in snapshots]
    assert max(counts) <= 12
    assert counts[0] == 12  # filled at once
    assert sorted(counts)[len(counts) // 10] >= 10  # 90 % of the time at least 10 of 12
    ego_path = [s.entity("Ego") for s in snapshots]
    assert ego_path[-1] is not None and ego_path[0] is not None
    assert math.dist((ego_path[0].x, ego_path[0].y), (ego_path[-1].x, ego_path[-1].y)) > 400.0
    seen: set[str] = set()
    categories: set[str] = set()
    for snapshot in snapshots:
        ego = snapshot.entity("Ego")
        assert ego is not None
        for state in snapshot.entities:
            if not state.name.startswith("traffic_"):
                continue
            categories.add(state.category)
            # Removed at the first update outside: at most one step (~2 m) beyond the ellipse.
            assert _ellipse(ego.x, ego.y, ego.heading, state.x, state.y) < 1.03
            if state.name not in seen:
                seen.add(state.name)
                assert math.dist((ego.x, ego.y), (state.x, state.y)) > 40.0 - 3.0
    assert len(seen) > 12  # vehicles left the ellipse and were replaced
    assert categories == {"car", "truck"}


def test_same_seed_same_traffic_other_seed_other_traffic(tmp_path: Path, nets: Path) -> None:
    first = _swarm_run(tmp_path, nets, seed=3, end=6.0)
    second = _swarm_run(tmp_path, nets, seed=3, end=6.0)
    other = _swarm_run(tmp_path, nets, seed=4, end=6.0)
    assert [s.entities for s in first] == [s.entities for s in second]
    assert [traffic_of(s) for s in first] != [traffic_of(s) for s in other]


def test_traffic_ids_are_stable_never_reused_and_without_gaps(tmp_path: Path, nets: Path) -> None:
    snapshots = _swarm_run(tmp_path, nets, seed=11)
    frames: dict[int, list[int]] = {}
    names: dict[int, str] = {}
    for index, snapshot in enumerate(snapshots):
        ids = [e.id for e in snapshot.entities]
        assert len(ids) == len(set(ids))
        for state in snapshot.entities:
            assert names.setdefault(state.id, state.name) == state.name
            frames.setdefault(state.id, []).append(index)
    for ident, seen in frames.items():
        assert seen == list(range(seen[0], seen[-1] + 1)), f"id {ident} has a gap"
    assert len(set(names.values())) == len(names)


def test_source_inserts_at_its_rate(tmp_path: Path, nets: Path) -> None:
    path = write(
        tmp_path,
        road=STRAIGHT,
        entities={"Ego": ("1", -1, 450.0, 0.0)},
        init_traffic=SOURCE.format(name="src", rate=0.5, s=20.0),
        end=20.0,
    )
    snapshots = run(path, nets)
    names = {name for s in snapshots for name in traffic_of(s)}
    assert 9 <= len(names) <= 11  # 0.5 per second over 20 s
    known: set[str] = set()
    for snapshot in snapshots:
        for name, (x, _) in traffic_of(snapshot).items():
            if name not in known:
                known.add(name)
                assert abs(x - 20.0) < 8.0  # appears at the source


def test_stop_action_ends_a_source(tmp_path: Path, nets: Path) -> None:
    stop = traffic_event("stop", '<TrafficAction trafficName="src"><TrafficStopAction/>'
                         "</TrafficAction>", at=5.0)  # fmt: skip
    path = write(
        tmp_path,
        road=STRAIGHT,
        entities={"Ego": ("1", -1, 450.0, 0.0)},
        init_traffic=SOURCE.format(name="src", rate=1.0, s=20.0),
        stories=stop,
        end=15.0,
    )
    snapshots = run(path, nets)
    late = {n for s in snapshots if s.time > 6.0 for n in traffic_of(s)}
    early = {n for s in snapshots if s.time <= 6.0 for n in traffic_of(s)}
    assert 4 <= len(early) <= 6
    assert late <= early  # nothing new after the stop; earlier vehicles drive on


def test_sink_removes_traffic_but_not_scenario_entities(tmp_path: Path, nets: Path) -> None:
    path = write(
        tmp_path,
        road=STRAIGHT,
        entities={"Ego": ("1", -1, 5.0, 12.0)},
        init_traffic=SOURCE.format(name="src", rate=1.0, s=60.0),
        stories=traffic_event("sink", SINK.format(radius=10.0, s=200.0), at=0.0),
        end=30.0,
    )
    snapshots = run(path, nets)
    assert all(s.entity("Ego") is not None for s in snapshots)
    ego = snapshots[-1].entity("Ego")
    assert ego is not None and ego.x > 300.0  # drove through the sink and on
    reached = {n for s in snapshots for n, (x, _) in traffic_of(s).items() if x > 185.0}
    assert len(reached) >= 10
    beyond = {n for s in snapshots for n, (x, _) in traffic_of(s).items() if x > 215.0}
    assert not beyond  # every vehicle reaching the sink was removed there


def test_memory_backend_and_open_space_cannot_host_traffic(tmp_path: Path, nets: Path) -> None:
    road = write(
        tmp_path,
        road=STRAIGHT,
        entities={"Ego": ("1", -1, 50.0, 10.0)},
        init_traffic=SOURCE.format(name="s", rate=1.0, s=20.0),
        name="road.xosc",
    )
    with pytest.raises(UnsupportedFeatureError, match="in-memory backend drives no traffic"):
        run(road, nets, backend=BackendChoice.MEMORY)
    open_space = tmp_path / "open.xosc"
    text = road.read_text(encoding="utf-8")
    text = text.replace(f'<LogicFile filepath="{STRAIGHT}"/>', "").replace(
        '<LanePosition roadId="1" laneId="-1" offset="0" s="50.0"/>', '<WorldPosition x="0" y="0"/>'
    ).replace('<LanePosition roadId="1" laneId="-1" offset="0" s="20.0"/>',
              '<WorldPosition x="20" y="0"/>')  # fmt: skip
    open_space.write_text(text, encoding="utf-8")
    with pytest.raises(UnsupportedFeatureError, match="no road network"):
        run(open_space, nets)


def test_corpus_swarm_runs_and_its_ego_matches_the_reference(tmp_path: Path) -> None:
    scenario = CORPUS / "xosc" / "swarm.xosc"
    report = scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=scenario,
            nets_dir=tmp_path,
            record=False,
            sut=SutConfig(takeover=Takeover.NEVER),
        )
    )
    assert report.outcome.verdict in (Verdict.PASSED, Verdict.FAILED), report.outcome.reason
    ref = references.load(CORPUS.parents[1] / "esmini-reference.json")
    key = references.find(ref, scenario)
    assert key is not None
    comparison = references.compare(
        key, ref[key], samples=report.samples, end_time=report.outcome.simulated_seconds
    )
    assert comparison.match, comparison
