"""esmini's ALKS_R157SM_Controller imitated (Regulation, ReferenceDriver and FSM models) on the
hard-braking-lead scenario: the lead 40 m ahead brakes at 8 m/s^2 from t = 2 s."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.sim.test_esmini_acc import run_controlled

_OVERRIDE = '<Property name="mode" value="override"/>'
_NO_CRUISE = '<Property name="cruise" value="false"/>'


def _speeds(tmp_path: Path, properties: str) -> list[float]:
    report = run_controlled(tmp_path, properties, kind="ALKS_R157SM_Controller")
    assert not report.intended
    return [sample[4] for sample in report.samples["Ego"]]


def test_reference_driver_brakes_after_perceiving_and_reacting(tmp_path: Path) -> None:
    # a lead decelerating harder than 5 m/s^2 is perceived after 0.4 s, the driver reacts
    # 0.75 s later: nothing changes before t = 3 s; then it brakes (jerk-limited) to a stop
    model = (
        '<Property name="model" value="ReferenceDriver"/><Property name="fullStop" value="true"/>'
    )
    speeds = _speeds(tmp_path, model + _OVERRIDE + _NO_CRUISE)
    assert speeds[:4] == pytest.approx([25.0] * 4)
    assert speeds[4] < 23.0
    assert speeds[-1] == 0.0


def test_regulation_model_brakes_at_six_metres_per_second_squared(tmp_path: Path) -> None:
    # critical once the time to collision is under dv / 12 m/s^2 + 0.45 s
    speeds = _speeds(
        tmp_path, '<Property name="model" value="Regulation"/>' + _OVERRIDE + _NO_CRUISE
    )
    assert speeds[:4] == pytest.approx([25.0] * 4)
    assert speeds[4] - speeds[5] == pytest.approx(6.0)


def test_fsm_model_brakes_between_its_fuzzy_limits(tmp_path: Path) -> None:
    # closing in on the braking lead: 0.75 s of reaction, then at most 6 m/s^2 (its critical
    # zone's braking), never harder
    fsm = '<Property name="model" value="FSM"/>'
    speeds = _speeds(tmp_path, fsm + _OVERRIDE + _NO_CRUISE)
    assert speeds[:3] == pytest.approx([25.0] * 3)
    assert 24.0 < speeds[3] < 25.0
    assert 4.0 < speeds[4] - speeds[5] <= 6.0 + 1e-9


def test_cruise_follows_the_lead_at_the_models_distance(tmp_path: Path) -> None:
    # the reference driver's cruise wants 2 m + 2 s x speed (52 m) behind the lead 40 m ahead:
    # it brakes at up to 4 m/s^2 at once
    speeds = _speeds(tmp_path, '<Property name="model" value="ReferenceDriver"/>' + _OVERRIDE)
    assert speeds[1] < 23.0


def test_rss_model_is_not_imitated(tmp_path: Path) -> None:
    report = run_controlled(
        tmp_path, '<Property name="model" value="RSS"/>', kind="ALKS_R157SM_Controller"
    )
    assert report.intended == ("controller ctrl of Ego not imitated",)
    assert report.samples["Ego"][1][4] == pytest.approx(25.0)
