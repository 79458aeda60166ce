"""Evidence quality and the re-evaluation verdict: the fast reader agrees with the plot reader, the
quality numbers agree with omega-prime's own qualification metrics, damaged recordings are
flagged, and a run on incomplete evidence is never ``Passed``."""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.evaluation import quality, reevaluating
from simtest_operator.evaluation.basescenarios import Kind
from simtest_operator.evaluation.scenes import scene_from_columns
from simtest_operator.recording import objects as objects_module
from simtest_operator.recording import read_trajectories
from simtest_operator.recording.objects import ObjectRecord, RecordedObjects, read_objects
from simtest_operator.snapshots import Discontinuity, JumpCause
from simtest_operator.verdicts import Verdict
from tests.evaluation import recorded_runs

pytestmark = pytest.mark.timeout(300)


@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("smoke")
    manifest = recorded_runs.write_manifest(
        folder,
        name="quality",
        source=recorded_runs.SCENARIOS / "smoke",
        include=["following_*.xosc", "pedestrian-crossing_*.xosc", "cut-in_highway_v30_*.xosc"],
    )
    out = recorded_runs.run_campaign(manifest, folder / "out")
    return {p.parent.name.split("_")[0]: p for p in (out / "scenarios").glob("*/recording.mcap")}


def test_the_fast_reader_agrees_with_the_trajectory_reader(recordings: dict[str, Path]) -> None:
    for path in recordings.values():
        decoded = read_objects(path)
        plotted = read_trajectories(path)
        assert set(decoded.objects) == set(plotted)
        for object_id, samples in plotted.items():
            record = decoded.objects[object_id]
            assert record.t == [s.t for s in samples]
            assert record.x == [s.x for s in samples] and record.y == [s.y for s in samples]
            assert record.yaw == [s.heading for s in samples]
            speeds = np.hypot(record.vx, record.vy)
            assert np.allclose(speeds, [s.speed for s in samples])
        assert decoded.map_xml is not None and decoded.map_xml.startswith("<?xml")
        assert decoded.map_references == {decoded.map_channel_reference}
        assert set(decoded.host_ids) == {min(decoded.objects)}


def test_the_layout_fast_path_decodes_like_the_general_decoder(
    recordings: dict[str, Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    fast = {name: read_objects(path) for name, path in recordings.items()}
    monkeypatch.setattr(objects_module, "_OBJECT_LAYOUT", re.compile(b"(?!)"))
    monkeypatch.setattr(objects_module, "_BASE_LAYOUT", re.compile(b"(?!)"))
    for name, path in recordings.items():
        general = read_objects(path)
        assert general.objects == fast[name].objects
        assert general.frame_times == fast[name].frame_times


def test_a_sound_recording_is_complete_evidence(recordings: dict[str, Path]) -> None:
    decoded = read_objects(recordings["following"])
    q = quality.assess(decoded, simulated_seconds=decoded.frame_times[-1])
    assert q.complete, q.issues
    assert q.metrics["rateHz"] == 10.0 and q.metrics["temporalCompleteness"] == 100.0
    assert q.metrics["duplicateRecordRate"] == 0.0
    assert q.metrics["dataFormatConsistency"] == 100.0


def _damaged(decoded: RecordedObjects) -> RecordedObjects:
    """Object 1 loses frames 30-39, one sample is duplicated, one yaw is out of range."""
    other = decoded.objects[1]
    keep = [i for i in range(len(other.t)) if not 30 <= i < 40]
    columns = {
        f.name: [getattr(other, f.name)[i] for i in keep]
        for f in dataclasses.fields(ObjectRecord)
        if f.name != "object_id"
    }
    for name, values in columns.items():
        values.insert(5, values[5])
        if name == "yaw":
            values[50] = 4.0
    damaged = ObjectRecord(object_id=1, **columns)
    return dataclasses.replace(decoded, objects={**decoded.objects, 1: damaged})


def test_quality_numbers_match_omega_primes_qualification_metrics(
    recordings: dict[str, Path],
) -> None:
    pl = pytest.importorskip("polars")
    qualification = pytest.importorskip("omega_prime.metrics.qualification")
    from omega_prime.schemas import polars_schema

    sound = read_objects(recordings["following"])
    for decoded in (sound, _damaged(sound)):
        rows = {name: [] for name in polars_schema}
        for o in decoded.objects.values():
            n = len(o.t)
            rows["total_nanos"] += [round(t * 1e9) for t in o.t]
            rows["idx"] += [o.object_id] * n
            for name in ("x", "y", "vx", "vy", "ax", "ay", "length", "width", "height",
                         "roll", "pitch", "yaw"):  # fmt: skip
                target = {"vx": "vel_x", "vy": "vel_y", "ax": "acc_x", "ay": "acc_y"}.get(
                    name, name
                )
                rows[target] += list(getattr(o, name))
            for name in ("z", "vel_z", "acc_z"):
                rows[name] += [0.0] * n
            rows["type"] += list(o.object_type)
            rows["role"] += list(o.role)
            rows["subtype"] += list(o.vehicle_type)
        frame = pl.DataFrame(rows, schema=polars_schema).lazy()
        ours = quality.assess(decoded, simulated_seconds=decoded.frame_times[-1])

        def value(metric: object, key: str, frame: object = frame, **kw: object) -> float:
            _, props = metric(frame, **kw)  # type: ignore[operator]
            return float(props[key].collect()[key][0])

        assert ours.metrics["temporalCompleteness"] == pytest.approx(
            value(
                qualification.temporal_completeness,
                "temporal_completeness",
                expected_frequency=ours.metrics["rateHz"],
            )
        )
        assert ours.metrics["duplicateRecordRate"] == pytest.approx(
            value(qualification.duplicate_record_rate, "duplicate_record_rate"), abs=1e-4
        )
        assert ours.metrics["dataFormatConsistency"] == pytest.approx(
            value(qualification.data_format_consistency, "data_format_consistency"), abs=1e-4
        )


def test_damaged_recordings_are_incomplete_evidence(recordings: dict[str, Path]) -> None:
    decoded = read_objects(recordings["following"])
    end = decoded.frame_times[-1]
    damaged = quality.assess(_damaged(decoded), simulated_seconds=end)
    text = " | ".join(damaged.issues)
    assert "temporal completeness 50.0 % < 100 %" in text
    assert "1 duplicate (object, time) record(s)" in text
    assert "1 value(s) out of omega-prime's ranges" in text
    moved = read_objects(recordings["following"])
    moved.objects[1].x[40] += 3.0
    jumped = quality.assess(moved, simulated_seconds=end)
    (issue,) = jumped.issues
    assert issue.startswith("object 1 jumps 2.9") and issue.endswith(
        f"m against its velocity at t={moved.objects[1].t[40]:.2f} s"
    )
    truncated = quality.assess(decoded, simulated_seconds=end + 5.0)
    assert truncated.issues == (
        f"recording ends at t={end:.2f} s, the run simulated {end + 5.0:.2f} s",
    )
    mapless = quality.assess(dataclasses.replace(decoded, map_xml=None), simulated_seconds=end)
    assert mapless.issues == ("no map (ground_truth_map channel) in the recording",)
    # A scenario without a road network records no map: nothing is missing then.
    open_space = quality.assess(
        dataclasses.replace(decoded, map_xml=None), simulated_seconds=end, map_expected=False
    )
    assert open_space.issues == ()
    # A scenario of signals only has no ego and no objects: nothing is missing either.
    empty = dataclasses.replace(decoded, objects={}, host_ids=tuple(None for _ in decoded.host_ids))
    assert quality.assess(empty, simulated_seconds=end, host_expected=False).issues == ()
    assert quality.assess(empty, simulated_seconds=end).issues == (
        "no host vehicle (ego) in the recording",
    )
    times = list(decoded.frame_times)
    gap = dataclasses.replace(decoded, frame_times=(*times[:20], *times[25:]))
    assert any("frame gap" in issue for issue in quality.assess(gap, simulated_seconds=end).issues)
    hostless = dataclasses.replace(decoded, host_ids=(None,) * len(times))
    assert any("host vehicle" in i for i in quality.assess(hostless, simulated_seconds=end).issues)


def test_incomplete_evidence_never_passes_but_a_violation_still_fails(
    recordings: dict[str, Path],
) -> None:
    decoded = read_objects(recordings["following"])
    scene = scene_from_columns(decoded)
    end = decoded.frame_times[-1]
    sound = quality.assess(decoded, simulated_seconds=end)
    partial = quality.assess(decoded, simulated_seconds=end + 5.0)
    lenient = reevaluating.DEFAULT_CRITERIA
    passed = reevaluating.evaluate(scene, sound, lenient, original=Verdict.PASSED)
    assert passed.verdict is Verdict.PASSED and passed.evidence == "complete"
    incomplete = reevaluating.evaluate(scene, partial, lenient, original=Verdict.PASSED)
    assert incomplete.verdict is Verdict.ERROR and incomplete.evidence == "incomplete"
    assert incomplete.reason.startswith("evidence incomplete: recording ends at")
    strict = reevaluating.load_criteria(
        {"name": "strict", "baseScenarios": {"following": {"minTHW": 5.0}}}, where="test"
    )
    failed = reevaluating.evaluate(scene, partial, strict, original=Verdict.PASSED)
    assert failed.verdict is Verdict.FAILED and failed.reason.startswith("following with object")
    assert "minTHW" in failed.reason and failed.evidence == "incomplete"
    missing = reevaluating.evaluate(None, None, lenient, original=Verdict.PASSED)
    assert (missing.verdict, missing.evidence) == (Verdict.ERROR, "missing")
    invalid = reevaluating.evaluate(None, None, lenient, original=Verdict.INVALID)
    assert invalid.verdict is Verdict.INVALID


def test_base_scenario_checks_use_the_thresholds_of_their_type(
    recordings: dict[str, Path],
) -> None:
    decoded = read_objects(recordings["cut-in"])
    scene = scene_from_columns(decoded)
    q = quality.assess(decoded, simulated_seconds=decoded.frame_times[-1])
    result = reevaluating.evaluate(scene, q, reevaluating.DEFAULT_CRITERIA, original=Verdict.FAILED)
    cut_in = next(s for s in result.base_scenarios if s.base.kind is Kind.CUT_IN)
    limits = {c.metric: c.limit for c in cut_in.checks}
    assert limits == {"minTTC": 1.0, "minTHW": 0.3, "maxDecel": 9.0, "collision": 0.0}
    assert cut_in.metrics["collision"] == 1.0 and cut_in.verdict is Verdict.FAILED
    assert result.verdict is Verdict.FAILED
    assert result.metrics["minDistance"] == 0.0
    assert math.isfinite(result.metrics["baseScenarios"])


def test_a_criteria_file_with_a_wrong_field_names_it() -> None:
    with pytest.raises(ScenarioError) as raised:
        reevaluating.load_criteria(
            {"name": "x", "baseScenarios": {"cut-in": {"minTCC": 1.0}}}, where="crit.yaml"
        )
    assert str(raised.value).startswith("crit.yaml: baseScenarios.cut-in.minTCC: ")
    with pytest.raises(ScenarioError, match=r"baseScenarios\.overtaking"):
        reevaluating.load_criteria({"name": "x", "baseScenarios": {"overtaking": {}}}, where="f")
    kept = reevaluating.load_criteria(
        {"name": "x", "baseScenarios": {"vru": {"PET": 2}}}, where="f"
    )
    assert kept.base_scenarios[Kind.VRU].pet == 2.0
    assert (
        kept.base_scenarios[Kind.CUT_IN]
        == reevaluating.DEFAULT_CRITERIA.base_scenarios[Kind.CUT_IN]
    )


def test_a_speed_that_steps_between_frames_is_explained(recordings: dict[str, Path]) -> None:
    # A step SpeedAction (or a start from rest) changes the speed within one frame interval:
    # the displacement is the new velocity's, not the trapezoid's mean of old and new.
    decoded = read_objects(recordings["following"])
    stepped = read_objects(recordings["following"])
    lead = stepped.objects[1]
    assert math.hypot(lead.vx[40], lead.vy[40]) > 5.0
    lead.vx[40] = lead.vy[40] = 0.0
    assert quality.assess(stepped, simulated_seconds=decoded.frame_times[-1]).issues == ()


def _teleported(decoded: RecordedObjects, frame: int, metres: float) -> RecordedObjects:
    """The lead (object 1) put ``metres`` further along x from ``frame`` on, velocities kept:
    the recording of a mid-run TeleportAction."""
    lead = decoded.objects[1]
    moved = dataclasses.replace(
        lead, x=[x + (metres if i >= frame else 0.0) for i, x in enumerate(lead.x)]
    )
    return dataclasses.replace(decoded, objects={**decoded.objects, 1: moved})


def _jump(time: float, object_id: int, cause: JumpCause = JumpCause.TELEPORT) -> Discontinuity:
    return Discontinuity(time=time, entity=object_id, cause=cause, object_id=object_id)


def test_a_declared_jump_is_excused_only_where_and_for_whom_it_was_declared(
    recordings: dict[str, Path],
) -> None:
    decoded = read_objects(recordings["following"])
    end = decoded.frame_times[-1]
    jumped = _teleported(decoded, 40, 20.0)
    at = jumped.objects[1].t[40]
    undeclared = quality.assess(jumped, simulated_seconds=end)
    assert any(
        re.fullmatch(rf"object 1 jumps 19\.\d\d m against its velocity at t={at:.2f} s", issue)
        for issue in undeclared.issues
    ), undeclared.issues
    declared = dataclasses.replace(jumped, discontinuities=(_jump(at, 1),))
    assert quality.assess(declared, simulated_seconds=end).issues == ()
    # The same jump declared for another entity, or for another frame, is still caught.
    for wrong in (_jump(at, 0), _jump(jumped.objects[1].t[41], 1), _jump(at - 0.1, 1)):
        misdeclared = dataclasses.replace(jumped, discontinuities=(wrong,))
        assert quality.assess(misdeclared, simulated_seconds=end).issues == undeclared.issues
    # A declaration excuses its own frame interval only: a second jump later is caught.
    twice = dataclasses.replace(_teleported(jumped, 60, 20.0), discontinuities=(_jump(at, 1),))
    issues = quality.assess(twice, simulated_seconds=end).issues
    later = jumped.objects[1].t[60]
    assert (
        len(issues) == 1
        and f"object 1 jumps 20.00 m against its velocity at t={later:.2f} s" in issues[0]
    )


def test_a_deleted_ego_is_not_due_in_the_frames_after_its_declared_deletion(
    recordings: dict[str, Path],
) -> None:
    decoded = read_objects(recordings["following"])
    end = decoded.frame_times[-1]
    ego = decoded.objects[0]
    kept = {
        f.name: getattr(ego, f.name)[:50]
        for f in dataclasses.fields(ObjectRecord)
        if f.name != "object_id"
    }
    deleted = dataclasses.replace(
        decoded, objects={**decoded.objects, 0: ObjectRecord(object_id=0, **kept)}
    )
    gone_at = decoded.frame_times[50]
    frames = len(decoded.frame_times)
    assert quality.assess(deleted, simulated_seconds=end).issues == (
        f"host vehicle 0 is in 50 of {frames} frames",
    )
    declared = dataclasses.replace(deleted, discontinuities=(_jump(gone_at, 0, JumpCause.DELETED),))
    assert quality.assess(declared, simulated_seconds=end).issues == ()
    # Added again at frame 70 but missing from the recording from then on: that is a gap.
    back = decoded.frame_times[70]
    readded = dataclasses.replace(
        declared, discontinuities=(*declared.discontinuities, _jump(back, 0, JumpCause.ADDED))
    )
    assert quality.assess(readded, simulated_seconds=end).issues == (
        f"host vehicle 0 is in 50 of {frames - 20} frames",
    )
