"""esmini's InteractiveController and ExternalController with nobody at the wheel (headless, no
process reporting): the interactive one keeps the speed it had on activation (less its engine
brake) and drives straight on; the external one leaves the entity standing. Under the default
takeover the SUT model drives the ego instead."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from simtest_operator.runner import scenario_execution
from simtest_operator.sim import Takeover
from tests.sim import osc_scenarios as osc
from tests.sim.test_reference_match import compare

DATA = Path(__file__).parent / "data"

_ACTIVATE = (
    '<ControllerAction><ActivateControllerAction longitudinal="true" lateral="true"/>'
    "</ControllerAction>"
)


def _run(
    tmp_path: Path,
    controller: str,
    *,
    activate_first: bool = False,
    entity: str = "Ego",
    takeover: Takeover = Takeover.NEVER,
) -> scenario_execution.RunReport:
    # hard_braking_lead: Ego at s = 20 and Lead at s = 60 on a straight road, both at 25 m/s;
    # the lead brakes at 8 m/s^2 from t = 2 s; the storyboard ends 3 s after that
    shutil.copy(DATA / "straight.xodr", tmp_path / "straight.xodr")
    text = (DATA / "hard_braking_lead.xosc").read_text(encoding="utf-8")
    text = osc.with_controller(text, entity, controller)
    if activate_first or entity != "Ego":
        text = text.replace(
            f"<PrivateAction>\n            {_ACTIVATE}\n          </PrivateAction>", ""
        )
        insert = f'<Private entityRef="{entity}">'
        position = text.index("</PrivateAction>", text.index(insert)) + len("</PrivateAction>")
        # right after the teleport: before the Init's SpeedAction
        text = text[:position] + f"<PrivateAction>{_ACTIVATE}</PrivateAction>" + text[position:]
    path = tmp_path / "controlled.xosc"
    path.write_text(text, encoding="utf-8")
    return osc.run(path, tmp_path, takeover=takeover)


_INTERACTIVE = '<Property name="esminiController" value="InteractiveController"/>'
_EXTERNAL = '<Property name="esminiController" value="ExternalController"/>'


def test_interactive_driver_keeps_its_speed_less_the_engine_brake(tmp_path: Path) -> None:
    # activated after the Init's SpeedAction: 25 m/s, 0.1 % less per step (no throttle), on
    # straight (no steering); the road has no speed limit and two lanes each way: 110 km/h
    report = _run(tmp_path, _INTERACTIVE)
    ego = report.samples["Ego"]
    assert ego[0][4] == pytest.approx(25.0)
    assert ego[2][4] == pytest.approx(25.0 * 0.999**40, rel=1e-4)
    assert ego[2][2] == pytest.approx(ego[0][2])  # straight on
    assert not report.intended


def test_interactive_driver_activated_before_the_speed_stands(tmp_path: Path) -> None:
    # esmini's interactive vehicle takes the speed at activation (0 before the Init's
    # SpeedAction) and, without throttle, never leaves it; the storyboard's speed is overridden
    report = _run(tmp_path, _INTERACTIVE, activate_first=True)
    ego = report.samples["Ego"]
    assert [sample[1] for sample in ego] == pytest.approx([ego[0][1]] * len(ego))
    assert [sample[4] for sample in ego] == [0.0] * len(ego)  # from t = 0: what others read


def test_speed_factor_scales_the_interactive_drivers_limit(tmp_path: Path) -> None:
    # half of 110 km/h caps the first step's speed, which then shrinks by the engine brake
    factor = '<Property name="speedFactor" value="0.5"/>'
    report = _run(tmp_path, _INTERACTIVE + factor)
    assert report.samples["Ego"][2][4] == pytest.approx(55 / 3.6 * 0.999**39, rel=1e-4)


def test_external_controller_without_reports_stands(tmp_path: Path) -> None:
    report = _run(tmp_path, _EXTERNAL, entity="Lead")
    lead = report.samples["Lead"]
    assert [sample[1] for sample in lead] == pytest.approx([lead[0][1]] * len(lead))
    assert lead[1][4] == 0.0
    assert not report.intended


def test_sut_takeover_drives_the_ego_instead(tmp_path: Path) -> None:
    report = _run(tmp_path, _EXTERNAL, takeover=Takeover.ON_CONTROLLER)
    ego = report.samples["Ego"]
    assert ego[1][1] > ego[0][1] + 10.0
    assert report.intended == ("Ego driven by the SUT model",)


@pytest.mark.parametrize(
    "relative",
    [
        "xosc/drive_when_close.xosc",  # interactive Ego stands: the target never starts
        "lookahead_along_route_all_opposite.xosc",  # external Ego stands, nobody reports
        "lookahead_along_route.xosc",  # external controller without ghost
    ],
)
def test_matches_the_reference_player(relative: str, tmp_path: Path) -> None:
    comparison = compare(relative, tmp_path)
    assert comparison.match, comparison
