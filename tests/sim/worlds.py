"""A small world for focused action tests: the straight 1 km road of ``data/straight.xodr``
(two lanes each way, 3.5 m wide) or the 300 m left arc of radius 50 m of ``data/arc.xodr`` (one
lane each way), cars on it, and a dispatcher that starts actions and steps
them like the engine does (runs, then motion)."""

from __future__ import annotations

from pathlib import Path

from simtest_operator.opendrive import RoadNetwork
from simtest_operator.openscenario import model
from simtest_operator.sim import motion
from simtest_operator.sim.actors import Actor, Domain, Mode
from simtest_operator.sim.dispatch import Dispatcher
from simtest_operator.sim.trajectories import PathRun
from simtest_operator.sim.world import World
from simtest_operator.snapshots import BoundingBox, EntityKind

DATA = Path(__file__).parent / "data"
DT = 0.05


def car(name: str) -> model.ScenarioObject:
    return model.ScenarioObject(
        name=name,
        kind=EntityKind.VEHICLE,
        category="car",
        bounding_box=BoundingBox(center_x=1.4, length=4.5, width=1.8),
        performance=model.Performance(max_speed=70.0, max_acceleration=10.0, max_deceleration=10.0),
    )


class Bench:
    """World + dispatcher on the straight road; :meth:`step` advances like the engine."""

    def __init__(self, *names: str, road: str | None = "straight.xodr") -> None:
        roads = RoadNetwork.from_file(DATA / road) if road is not None else None
        actors = [Actor(car(name), index) for index, name in enumerate(names)]
        self.world = World(roads=roads, actors=actors, dt=DT, seed=1, parameters={}, variables={})
        self.dispatcher = Dispatcher(self.world, ego=None, switch=lambda actor, on: None)
        self.steps = 0

    def actor(self, name: str) -> Actor:
        return self.world.actor(name)

    def start(self, name: str, body: model.AnyAction) -> None:
        self.dispatcher.start_private(self.actor(name), body)

    def step(self, count: int = 1) -> None:
        world = self.world
        for _ in range(count):
            world.freeze()
            for actor in world.actors.values():
                if not actor.placed:
                    continue
                before = (actor.road_id, actor.lane_id, actor.offset)
                start = (actor.x, actor.y)
                runs = self.dispatcher.runs(actor)
                lateral = runs.get(Domain.LATERAL)
                for run in dict.fromkeys(runs.values()):
                    run.step(world, DT)
                placed = actor.mode is Mode.PATH or (
                    isinstance(lateral, PathRun) and lateral.finished and not lateral.stopped
                )
                motion.move(world, actor, DT, before=before, start=start, placed=placed)
            world.refresh()
            for run in self.dispatcher.active():
                run.after_motion(world)
            self.steps += 1
            world.time = round(self.steps * DT, 9)
            world.date_jumps()  # as the engine does when it builds the snapshot


def lane(lane_id: int, s: float, offset: float = 0.0, h: float | None = None) -> model.Position:
    orientation = (
        model.Orientation(type=model.ReferenceContext.RELATIVE, h=h) if h is not None else None
    )
    return model.LanePosition(
        road_id="1", lane_id=lane_id, s=s, offset=offset, orientation=orientation
    )


def teleport(position: model.Position) -> model.TeleportAction:
    return model.TeleportAction(position=position)


def speed(value: float) -> model.SpeedAction:
    return model.SpeedAction(
        dynamics=model.TransitionDynamics(
            shape=model.DynamicsShape.STEP, dimension=model.DynamicsDimension.TIME, value=0.0
        ),
        target=model.AbsoluteTargetSpeed(value=value),
    )
