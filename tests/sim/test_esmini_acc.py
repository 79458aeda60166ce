"""esmini's ACCController imitated: towards its set speed without a lead, a following distance of
3 m plus the time gap behind one (here a lead braking to a stop)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from simtest_operator.runner import scenario_execution

from . import osc_scenarios as osc

DATA = Path(__file__).parent / "data"


def run_controlled(
    tmp_path: Path, properties: str, *, gap: float = 40.0, kind: str = "ACCController"
) -> scenario_execution.RunReport:
    # hard_braking_lead: Ego at s = 20 and Lead ``gap`` m ahead, both at 25 m/s (Ego's
    # controller activated after the Init's SpeedAction); the lead brakes at 8 m/s^2 from
    # t = 2 s to a stop; Ego's car accelerates at up to 5 m/s^2
    shutil.copy(DATA / "straight.xodr", tmp_path / "straight.xodr")
    text = (DATA / "hard_braking_lead.xosc").read_text(encoding="utf-8")
    text = text.replace('value="40"', f'value="{gap}"')  # the Gap parameter
    text = osc.with_controller(
        text, "Ego", f'<Property name="esminiController" value="{kind}"/>{properties}'
    )
    path = tmp_path / "controlled.xosc"
    path.write_text(text, encoding="utf-8")
    return osc.run(path, tmp_path)


_OVERRIDE = '<Property name="mode" value="override"/><Property name="setSpeed" value="30"/>'


def test_without_lead_it_approaches_the_set_speed(tmp_path: Path) -> None:
    # the lead 200 m ahead is beyond the lookahead (50 m or twice the stopping distance):
    # at most 0.7 x 5 m/s^2, 3.5 m/s^2 per m/s short of 30 m/s, never past it
    report = run_controlled(tmp_path, _OVERRIDE, gap=200.0)
    ego = report.samples["Ego"]
    assert ego[1][4] == pytest.approx(28.5, abs=1e-6)
    assert 29.9 < ego[2][4] <= 30.0
    assert ego[4][4] == pytest.approx(30.0, abs=1e-3)
    assert not report.intended


def test_additive_mode_takes_the_speed_at_activation_as_set_speed(tmp_path: Path) -> None:
    report = run_controlled(tmp_path, '<Property name="setSpeed" value="30"/>', gap=200.0)
    assert [sample[4] for sample in report.samples["Ego"][:5]] == pytest.approx([25.0] * 5)
    assert not report.intended


def test_it_slows_down_behind_a_lead_braking_to_a_stop(tmp_path: Path) -> None:
    report = run_controlled(tmp_path, _OVERRIDE)
    ego, lead = report.samples["Ego"], report.samples["Lead"]
    # 40 m ahead is closer than 3 m + 1.5 s x 25 m/s: it starts falling back at once
    assert ego[1][4] < 25.0
    speeds = [sample[4] for sample in ego[2:]]
    assert speeds == sorted(speeds, reverse=True)
    assert ego[-1][4] < 2.0  # the lead stands: it creeps up to 3 m behind it
    gap = lead[-1][1] - ego[-1][1] - 4.5  # reference points on the same place of equal boxes
    assert 3.0 < gap < 8.0
    assert "collided" not in report.outcome.reason


def test_alks_controller_is_the_acc(tmp_path: Path) -> None:
    # esmini's older ALKSController inherits the ACC: additive without a mode, it slows down
    # behind the lead 40 m ahead (3 m + 1.5 s x 25 m/s wanted)
    report = run_controlled(tmp_path, "", kind="ALKSController")
    assert report.samples["Ego"][1][4] < 25.0
    assert not report.intended
