"""Traffic signals: a TrafficSignalStateAction sets a signal's state and a TrafficSignalCondition
reads it (exact state string, unknown signals match nothing); RoadNetwork controllers cycle their
phases (a state action holds until the next phase), start after a referenced controller, switch
phase by TrafficSignalControllerAction and are read by TrafficSignalControllerCondition."""

from __future__ import annotations

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import model
from simtest_operator.sim.condition_checks import Conditions
from simtest_operator.sim.world import World
from tests.sim.worlds import Bench


def test_state_action_sets_what_the_condition_reads() -> None:
    bench = Bench("Car")
    conditions = Conditions(bench.world, lambda *args: False)

    def shows(name: str, state: str) -> bool:
        body = model.ByValue(condition=model.TrafficSignalCondition(name=name, state=state))
        return conditions(body)[0]

    assert not shows("1", "off;off;on")
    bench.dispatcher.start_global(model.TrafficSignalStateAction(name="1", state="off;off;on"))
    assert shows("1", "off;off;on")
    assert not shows("1", "on;off;off") and not shows("2", "off;off;on")


def controller(
    name: str, *phases: tuple[str, float, str], delay: float = 0.0, reference: str | None = None
) -> model.TrafficSignalController:
    """A controller whose phases each set signal "1" (name, duration, state)."""
    return model.TrafficSignalController(
        name=name,
        phases=tuple(
            model.Phase(name=phase, duration=duration, states=(("1", state),))
            for phase, duration, state in phases
        ),
        delay=delay,
        reference=reference,
    )


RED_GREEN = (("stop", 10.0, "red"), ("go", 5.0, "green"))


def test_controller_cycles_its_phases_and_a_state_action_holds_until_the_next_phase() -> None:
    world = World(
        roads=None, actors=(), dt=0.1, seed=1, parameters={}, variables={},
        controllers=(controller("c", *RED_GREEN),),
    )  # fmt: skip
    controllers = world.signal_controllers
    seen = []
    for time in (0.0, 9.9, 10.0, 14.9, 15.0, 25.0, 30.0):
        controllers.update(time)
        seen.append((controllers.phase("c"), world.signals["1"]))
        if time == 10.0:
            world.signals["1"] = "yellow"  # as a TrafficSignalStateAction does
    assert seen == [
        ("stop", "red"), ("stop", "red"), ("go", "green"), ("go", "yellow"),
        ("stop", "red"), ("go", "green"), ("stop", "red"),
    ]  # fmt: skip


def test_delay_after_a_reference_and_switching_phase() -> None:
    first = controller("a", *RED_GREEN)
    second = controller("b", *RED_GREEN, delay=10.0, reference="a")
    world = World(
        roads=None, actors=(), dt=0.1, seed=1, parameters={}, variables={},
        controllers=(first, second),
    )  # fmt: skip
    controllers = world.signal_controllers
    controllers.update(0.0)
    # b's first phase starts 10 s after a's: at t=0 it is 5 s into its cycle's "stop" phase.
    assert (controllers.phase("a"), controllers.phase("b")) == ("stop", "stop")
    controllers.update(6.0)
    assert controllers.phase("b") == "go"
    controllers.switch("a", "go", 7.0)
    assert controllers.phase("a") == "go"
    controllers.update(11.9)
    assert controllers.phase("a") == "go"
    controllers.update(12.0)
    assert controllers.phase("a") == "stop"
    with pytest.raises(ScenarioError, match="has no phase 'amber' \\(phases: stop, go\\)"):
        controllers.switch("a", "amber", 12.0)
    with pytest.raises(ScenarioError, match="'z' is not declared"):
        controllers.phase("z")


def test_controller_action_and_condition_through_the_engine_parts() -> None:
    bench = Bench("Car")
    world = World(
        roads=None, actors=(), dt=0.1, seed=1, parameters={}, variables={},
        controllers=(controller("c", *RED_GREEN),),
    )  # fmt: skip
    bench.world.signal_controllers = world.signal_controllers
    conditions = Conditions(bench.world, lambda *args: False)
    in_phase = model.ByValue(
        condition=model.TrafficSignalControllerCondition(controller_ref="c", phase="go")
    )
    bench.world.signal_controllers.update(0.0)
    assert not conditions(in_phase)[0]
    bench.dispatcher.start_global(
        model.TrafficSignalControllerAction(controller_ref="c", phase="go")
    )
    assert conditions(in_phase)[0]
