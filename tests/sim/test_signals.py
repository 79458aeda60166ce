"""Traffic signals: a TrafficSignalStateAction sets a signal's state and a TrafficSignalCondition
reads it (exact state string, unknown signals match nothing)."""

from __future__ import annotations

from simtest_operator.openscenario import model
from simtest_operator.sim.condition_checks import Conditions
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
