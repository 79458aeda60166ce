"""``simtest scenario check``/``run`` show accepted schema deviations; ``--strict`` refuses them.

Covers: a file with ``parameterType="int"`` runs with a warning line naming code and line (run)
and a warnings cell (check), and is Invalid under ``--strict`` (exit 2); a file named
``a[/x].xosc`` and a reason holding ``[bold]`` print verbatim in the check table (no rich markup,
no MarkupError); --max-scenario-mb and a LogicFile out to /etc/passwd make `run` Invalid (exit 2).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator.cli.main import cli

pytestmark = pytest.mark.timeout(120)

OPEN_SPACE = """<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="1" date="2024-01-01T00:00:00" description="d" author="t"/>
  <ParameterDeclarations>
    <ParameterDeclaration name="Speed" parameterType="int" value="10"/>
  </ParameterDeclarations>
  <Entities>
    <ScenarioObject name="Ego">
      <Vehicle name="car" vehicleCategory="car">
        <BoundingBox><Center x="1.4" y="0" z="0.75"/><Dimensions width="2" length="5" height="1.5"/>
        </BoundingBox>
        <Performance maxSpeed="69" maxAcceleration="10" maxDeceleration="10"/>
        <Axles>
          <FrontAxle maxSteering="0.5" wheelDiameter="0.8" trackWidth="1.7" positionX="2.9"
                     positionZ="0.4"/>
          <RearAxle maxSteering="0" wheelDiameter="0.8" trackWidth="1.7" positionX="0"
                    positionZ="0.4"/>
        </Axles>
      </Vehicle>
    </ScenarioObject>
  </Entities>
  <Storyboard>
    <Init><Actions><Private entityRef="Ego">
      <PrivateAction><TeleportAction><Position><WorldPosition x="0" y="0" h="0"/></Position>
      </TeleportAction></PrivateAction>
      <PrivateAction><LongitudinalAction><SpeedAction>
        <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
        <SpeedActionTarget><AbsoluteTargetSpeed value="$Speed"/></SpeedActionTarget>
      </SpeedAction></LongitudinalAction></PrivateAction>
    </Private></Actions></Init>
    <StopTrigger><ConditionGroup><Condition name="t" delay="0" conditionEdge="rising">
      <ByValueCondition><SimulationTimeCondition value="1" rule="greaterThan"/></ByValueCondition>
    </Condition></ConditionGroup></StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"""


def _invoke(tmp_path: Path, *args: str) -> tuple[int, str]:
    env = {"SIMTEST_CACHE_DIR": str(tmp_path / "cache"), "COLUMNS": "250"}
    result = CliRunner().invoke(cli, ["scenario", *args], env=env)
    assert result.exception is None or isinstance(result.exception, SystemExit), result.output
    return result.exit_code, result.output


def test_run_prints_the_deviation_and_strict_refuses_it(tmp_path: Path) -> None:
    path = tmp_path / "int.xosc"
    path.write_text(OPEN_SPACE, encoding="utf-8")
    code, output = _invoke(tmp_path, "run", str(path), "--no-record")
    assert code == 0, output
    assert "warning: parameterType 'int' read as 'integer' (schema spelling) " in output
    assert f"[parameter-type-int] ({path}:5 <ParameterDeclaration>)" in output
    code, output = _invoke(tmp_path, "run", str(path), "--no-record", "--strict")
    assert code == 2, output
    assert output.startswith("verdict: Invalid\nreason: not schema-conformant (strict mode)")


def test_check_lists_warnings_and_never_reads_markup(tmp_path: Path) -> None:
    folder = tmp_path / "suite"
    folder.mkdir()
    (folder / "a[").mkdir()  # the id "a[/x].xosc" is a path: folder "a[", file "x].xosc"
    (folder / "a[" / "x].xosc").write_text(OPEN_SPACE, encoding="utf-8")
    (folder / "b[bold].xosc").write_text(  # Invalid: its reason quotes "[bold]Ego"
        OPEN_SPACE.replace('entityRef="Ego"', 'entityRef="[bold]Ego"'), encoding="utf-8"
    )
    code, output = _invoke(tmp_path, "check", str(folder), "-j", "1")
    assert code == 0, output
    assert "MarkupError" not in output
    assert "a[/x].xosc" in output and "b[bold].xosc" in output
    assert "[parameter-type-int]" in output
    assert output.count("line 5: parameterType 'int' read as") == 2
    assert "'[bold]Ego'" in output
    assert "1 ran, 1 invalid, 0 errors" in output
    assert "2 scenarios accepted with deviations from the schema" in output
    code, output = _invoke(tmp_path, "check", str(folder), "-j", "1", "--strict")
    assert "0 ran, 2 invalid, 0 errors" in output
    shutil.rmtree(folder)


def test_check_names_a_folder_with_markup_and_escapes_control_characters(
    tmp_path: Path,
) -> None:
    folder = tmp_path / "s[" / "x]"  # the folder "s[/x]" (issue 29): the table's title
    folder.mkdir(parents=True)
    (folder / "b\x1b[2J\u202e.xosc").write_text(OPEN_SPACE, encoding="utf-8")
    code, output = _invoke(tmp_path, "check", str(folder), "-j", "1")
    assert code == 0, output
    assert f"scenarios under {folder}" in output
    assert "b\\x1b[2J\\u202e.xosc" in output
    assert "\x1b" not in output and "\u202e" not in output
    code, output = _invoke(tmp_path, "run", str(folder / "b\x1b[2J\u202e.xosc"), "--no-record")
    assert code == 0, output


def test_size_limit_and_escapes_are_invalid(tmp_path: Path) -> None:
    path = tmp_path / "int.xosc"
    path.write_text(OPEN_SPACE, encoding="utf-8")
    code, output = _invoke(tmp_path, "run", str(path), "--no-record", "--max-scenario-mb", "0.001")
    assert code == 2, output
    assert output.startswith("verdict: Invalid\nreason: file is larger than the")
    escape = Path(__file__).resolve().parents[1] / "openscenario" / "carla" / "escape_passwd.xosc"
    code, output = _invoke(tmp_path, "run", str(escape), "--no-record")
    assert code == 2, output
    assert "reason: road network file '../../../../../../../../etc/passwd' refused" in output
    assert "hint: --root DIR" in output
