"""Fuzz targets for the readers of untrusted input: one function per reader, ``bytes -> None``.

The contract every target checks: any input either loads or raises the project's own
:class:`~simtest_operator.errors.SimtestError` whose message is one line (what a verdict's reason
and the CLI show). Any other exception, a multi-line message, a hang (libFuzzer's per-input
timeout) or a memory blow-up (its RSS limit) is a bug.
The same functions replay the committed corpus under pytest and run under atheris
(``python -m tests.fuzz``), so a crash found by fuzzing becomes a corpus file and a test.
"""

from __future__ import annotations

import contextlib
import math
import struct
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

from simtest_operator.errors import SimtestError

Target = Callable[[bytes], None]

_XODR_TEMPLATE = """<?xml version="1.0"?>
<OpenDRIVE><header revMajor="1" revMinor="6"/>
<road id="1" length="{0}" junction="-1"><planView>
<geometry s="0" x="{1}" y="{2}" hdg="{3}" length="{0}"><spiral curvStart="{4}" curvEnd="{5}"/>
</geometry>
<geometry s="{0}" x="0" y="0" hdg="0" length="{6}"><paramPoly3 aU="0" bU="{7}" cU="{8}" dU="{9}"
 aV="0" bV="{10}" cV="{11}" dV="{12}" pRange="arcLength"/></geometry></planView>
<lanes><laneOffset s="0" a="{13}" b="0" c="0" d="{14}"/><laneSection s="0">
<left><lane id="1" type="driving"><width sOffset="0" a="{15}" b="{16}" c="0" d="{17}"/></lane>
</left><center><lane id="0" type="none"/></center>
<right><lane id="-1" type="driving"><border sOffset="0" a="{18}" b="0" c="{19}" d="0"/></lane>
</right></laneSection></lanes></road></OpenDRIVE>
"""
_XODR_SLOTS = 20


@contextlib.contextmanager
def _refused_in_one_line() -> Iterator[None]:
    """Let a SimtestError through as a refusal if its message is one line; fail otherwise."""
    try:
        yield
    except SimtestError as exc:
        message = str(exc)
        if "\n" in message or "\r" in message:
            raise AssertionError(f"{type(exc).__name__} spans lines: {message[:500]!r}") from exc


def _numbers(data: bytes, count: int) -> list[float]:
    """``count`` doubles from ``data`` (zero-padded): NaN, inf, huge and tiny values included."""
    padded = data[: 8 * count].ljust(8 * count, b"\0")
    return list(struct.unpack(f"<{count}d", padded))


def _format(value: float) -> str:
    return repr(value) if math.isfinite(value) else str(value)


def xodr(data: bytes) -> None:
    """OpenDRIVE: parse, build the road network, then query it (pose on a lane, projection).

    A first byte ``0x00`` fills a road template's numbers from the rest (structure-aware: every
    input is well-formed XML, so the mutations reach the number checks and the evaluators);
    anything else is parsed as the XML document itself.
    """
    from simtest_operator.opendrive import RoadNetwork, flat_curves_rewritten

    if data[:1] == b"\0":
        values = [_format(value) for value in _numbers(data[1:], _XODR_SLOTS)]
        data = _XODR_TEMPLATE.format(*values).encode()
    with _refused_in_one_line():
        network = RoadNetwork.from_bytes(data, source="fuzz.xodr")
        for road in network.document.roads[:3]:
            for lane in network.lane_ids(road.id, 0.5 * road.length)[:2]:
                pose = network.lane_pose(road.id, 0.5 * road.length, lane)
                network.to_road(pose.x, pose.y)
    if data.startswith(b"<?xml"):  # netconvert's input: rewriting must keep the document valid
        with _refused_in_one_line():
            rewritten = flat_curves_rewritten(data, source="fuzz.xodr")
            if rewritten is not None:
                RoadNetwork.from_bytes(rewritten, source="rewritten.xodr")


def xosc(data: bytes) -> None:
    """OpenSCENARIO: load a scenario file (parameters, ``${...}``, catalogs, storyboard).

    A first byte ``0x00`` fills a scenario template's numbers (sizes, speeds, dynamics, delays,
    durations, distances) from the rest, as the xodr target does for roads.
    """
    from simtest_operator.openscenario import LoadOptions, load_scenario

    if data[:1] == b"\0":
        values = [_format(value) for value in _numbers(data[1:], _XOSC_SLOTS)]
        data = _XOSC_TEMPLATE.format(*values).encode()
    with tempfile.TemporaryDirectory(prefix="fuzz-xosc-") as folder:
        path = Path(folder) / "scenario.xosc"
        path.write_bytes(data)
        (Path(folder) / "road.xodr").write_bytes(_road())  # the seeds' LogicFile
        with _refused_in_one_line():
            load_scenario(path, options=LoadOptions(source_root=Path(folder)))


_XOSC_TEMPLATE = """<?xml version="1.0"?>
<OpenSCENARIO><FileHeader revMajor="1" revMinor="2" date="2024-01-01T00:00:00" description="f"
 author="f"/><ParameterDeclarations/><CatalogLocations/>
<RoadNetwork><LogicFile filepath="road.xodr"/></RoadNetwork><Entities>
<ScenarioObject name="Ego"><Vehicle name="car" vehicleCategory="car"><BoundingBox>
<Center x="{0}" y="0" z="0.75"/><Dimensions width="{1}" length="{2}" height="1.5"/></BoundingBox>
<Performance maxSpeed="{3}" maxAcceleration="10" maxDeceleration="{4}"/><Axles>
<FrontAxle maxSteering="0.5" wheelDiameter="0.8" trackWidth="1.7" positionX="2.9" positionZ="0.4"/>
<RearAxle maxSteering="0" wheelDiameter="0.8" trackWidth="1.7" positionX="0" positionZ="0.4"/>
</Axles><Properties/></Vehicle></ScenarioObject></Entities><Storyboard><Init><Actions>
<Private entityRef="Ego"><PrivateAction><TeleportAction><Position>
<LanePosition roadId="1" laneId="-1" s="{5}" offset="{6}"/></Position></TeleportAction>
</PrivateAction><PrivateAction><LongitudinalAction><SpeedAction><SpeedActionDynamics
 dynamicsShape="linear" value="{7}" dynamicsDimension="rate"/><SpeedActionTarget>
<AbsoluteTargetSpeed value="{8}"/></SpeedActionTarget></SpeedAction></LongitudinalAction>
</PrivateAction></Private></Actions></Init><Story name="s"><Act name="a"><ManeuverGroup
 name="g" maximumExecutionCount="1"><Actors selectTriggeringEntities="false"><EntityRef
 entityRef="Ego"/></Actors><Maneuver name="m"><Event name="e" priority="override"><Action
 name="lc"><PrivateAction><LateralAction><LaneChangeAction><LaneChangeActionDynamics
 dynamicsShape="sinusoidal" value="{9}" dynamicsDimension="time"/><LaneChangeTarget>
<RelativeTargetLane entityRef="Ego" value="1"/></LaneChangeTarget></LaneChangeAction>
</LateralAction></PrivateAction></Action><StartTrigger><ConditionGroup><Condition name="c"
 delay="{10}" conditionEdge="rising"><ByEntityCondition><TriggeringEntities
 triggeringEntitiesRule="any"><EntityRef entityRef="Ego"/></TriggeringEntities><EntityCondition>
<TimeHeadwayCondition entityRef="Ego" value="{11}" freespace="true" rule="lessThan"/>
</EntityCondition></ByEntityCondition></Condition></ConditionGroup></StartTrigger></Event>
</Maneuver></ManeuverGroup><StartTrigger><ConditionGroup><Condition name="t" delay="0"
 conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="{12}" rule="greaterThan"/>
</ByValueCondition></Condition></ConditionGroup></StartTrigger></Act></Story><StopTrigger>
<ConditionGroup><Condition name="end" delay="0" conditionEdge="none"><ByEntityCondition>
<TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="Ego"/></TriggeringEntities>
<EntityCondition><StandStillCondition duration="{13}"/></EntityCondition></ByEntityCondition>
</Condition></ConditionGroup></StopTrigger></Storyboard></OpenSCENARIO>
"""
_XOSC_SLOTS = 14


def _road() -> bytes:
    return (CORPUS / "xodr" / "rural_curved.xodr").read_bytes()


_PARAMETERS: dict[str, float | bool | str] = {"speed": 25.0, "on": True, "name": "ego", "z": 0.0}


def expression(data: bytes) -> None:
    """The ``${...}`` evaluator, with a few parameters of each type defined."""
    from simtest_operator.errors import ScenarioError
    from simtest_operator.openscenario.expressions import evaluate

    def lookup(name: str) -> float | bool | str:
        try:
            return _PARAMETERS[name]
        except KeyError:
            raise ScenarioError(f"parameter {name!r} is not declared") from None

    text = data.decode("utf-8", errors="replace")
    value: object = None
    with _refused_in_one_line():
        value = evaluate(text, lookup)
    if isinstance(value, float) and not math.isfinite(value):
        raise AssertionError(f"evaluate({text!r}) returned {value!r}")


def manifest(data: bytes) -> None:
    """A TestCampaign manifest: the YAML reader and the API model validation."""
    from simtest_operator.api import manifestfiles
    from simtest_operator.api.v1alpha1 import parse_campaign

    with tempfile.TemporaryDirectory(prefix="fuzz-manifest-") as folder:
        path = Path(folder) / "campaign.yaml"
        path.write_bytes(data)
        with _refused_in_one_line():
            _, documents = manifestfiles.read(path)
            for document in documents[:2]:
                parse_campaign(document, source=str(path))


TARGETS: dict[str, Target] = {
    "xodr": xodr,
    "xosc": xosc,
    "expression": expression,
    "manifest": manifest,
}
"""Target name -> function; the name is also the corpus folder under ``corpus/``."""

INSTRUMENTED = {
    "xodr": ("simtest_operator.opendrive", "simtest_operator.xmlsafe"),
    "xosc": ("simtest_operator.openscenario", "simtest_operator.xmlsafe"),
    "expression": ("simtest_operator.openscenario.expressions",),
    "manifest": ("simtest_operator.api.manifestfiles", "simtest_operator.api.v1alpha1"),
}
"""Packages atheris instruments for coverage feedback, per target."""

CORPUS = Path(__file__).resolve().parent / "corpus"
