"""Builds output folders as ``simtest run`` leaves them, for the report, CLI and browser tests.

A folder holds ``results.sqlite`` (written through the real store), per-scenario result JSON
files (one with metric timelines) and real omega-prime recordings written by
:class:`simtest_operator.recording.Recorder`: a cut-in where the cutter merges into the ego's
lane, and a pedestrian crossing.
"""

from __future__ import annotations

import dataclasses
import datetime
import json
import math
from pathlib import Path

from simtest_operator import recording, results
from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState, WorldSnapshot
from simtest_operator.verdicts import Verdict
from tests.results.resultdata import T0, sample_run, scenario


def _cut_in(t: float) -> tuple[EntityState, ...]:
    ego = EntityState(id=0, name="ego", kind=EntityKind.VEHICLE, category="car",
                      x=20.0 * t, y=-1.75, speed=20.0)  # fmt: skip
    lateral = -1.75 + 3.5 * max(0.0, 1.0 - max(0.0, t - 3.0) / 3.0)
    cutter = EntityState(id=1, name="cutter", kind=EntityKind.VEHICLE, category="car",
                         x=25.0 + 15.0 * t, y=lateral, speed=15.0)  # fmt: skip
    return ego, cutter


def _crossing(t: float) -> tuple[EntityState, ...]:
    ego = EntityState(id=0, name="ego", kind=EntityKind.VEHICLE, category="car",
                      x=10.0 * t, y=0.0, speed=10.0)  # fmt: skip
    walker = EntityState(id=1, name="walker", kind=EntityKind.PEDESTRIAN, category="pedestrian",
                         x=60.0, y=-8.0 + 1.4 * t, speed=1.4,
                         box=BoundingBox(length=0.5, width=0.6, height=1.8))  # fmt: skip
    return ego, walker


def write_recording(path: Path, scenario_id: str, crossing: bool = False) -> Path:
    """A 10 s, 10 Hz recording of the cut-in (or the pedestrian crossing)."""
    motion = _crossing if crossing else _cut_in
    info = recording.RecordingInfo(scenario_id=scenario_id, seed=42)
    with recording.Recorder(path, info=info) as recorder:
        for step in range(101):
            recorder.write(WorldSnapshot(time=step / 10, entities=motion(step / 10)))
    return path


def make_outdir(root: Path, *, previous: bool = False, database: str | None = None) -> Path:
    """An output folder of the sample run, or (``previous``) of an earlier run to compare with;
    the results go to ``database`` (a DSN) instead of the folder's SQLite file when given."""
    root.mkdir(parents=True, exist_ok=True)
    record, stored, listed = sample_run()
    if previous:
        record, stored, listed = _previous(record, stored, listed)
    with results.open_store(database or root) as store:
        key = store.begin_campaign(record.info, scenarios=listed, run_key=record.run_key)
        for entry in stored:
            store.add_outcome(key, entry.scenario, entry.outcome, recorded_at=T0)
        if record.finished_at is not None:
            store.finish_campaign(key, finished_at=record.finished_at, phase=record.phase)
    if not previous:
        close = root / "cut-in/close.xosc"
        close.mkdir(parents=True)
        write_recording(close / "recording.mcap", "cut-in/close.xosc")
        ttc = [[t / 10, (25.0 + 5 * t / 10) / 5.0 if t < 40 else 0.4 + (t - 40) / 100]
               for t in range(0, 101, 2)]  # fmt: skip
        ttc[10][1] = math.inf  # no vehicle ahead for a moment: a gap in the plot
        (close / "result.json").write_text(
            json.dumps({"scenarioId": "cut-in/close.xosc", "verdict": "Failed",
                        "timelines": {"ttc": {"unit": "s", "points": ttc},
                                      "egoSpeed": [[t / 10, 20.0] for t in range(101)]}}),
            encoding="utf-8",
        )  # fmt: skip
        crossing = root / "ped/crossing.xosc"
        crossing.mkdir(parents=True)
        write_recording(crossing / "recording.mcap", "ped/crossing.xosc", crossing=True)
    return root


def _previous(
    record: results.CampaignRecord,
    stored: list[results.StoredOutcome],
    listed: list[results.ScenarioInfo],
) -> tuple[results.CampaignRecord, list[results.StoredOutcome], list[results.ScenarioInfo]]:
    """Yesterday's run: cut-in/close passed (now regressed), follow/stop failed (now fixed),
    ped/night timed out too (still failing), old/gone.xosc existed, never/ran.xosc did not."""
    before = {"cut-in/close.xosc": Verdict.PASSED, "follow/stop.xosc": Verdict.FAILED}
    changed = []
    for entry in stored:
        verdict = before.get(entry.scenario.scenario_id)
        if verdict is not None:
            entry = dataclasses.replace(
                entry,
                outcome=dataclasses.replace(entry.outcome, verdict=verdict, reason="", attempts=1),
            )
        changed.append(entry)
    gone = scenario("old/gone.xosc", category="cut-in")
    changed.append(
        results.StoredOutcome(
            scenario=gone,
            outcome=dataclasses.replace(stored[1].outcome, scenario_id="old/gone.xosc"),
        )
    )
    kept = [s for s in listed if s.scenario_id != "never/ran.xosc"] + [gone]
    earlier = dataclasses.replace(
        record,
        run_key=results.RunKey("smoke-20250228T120000Z-00c0ffee"),
        info=dataclasses.replace(
            record.info, started_at=T0 - datetime.timedelta(days=1), sut_version="1.3.0"
        ),
        finished_at=T0 - datetime.timedelta(days=1) + datetime.timedelta(seconds=40),
    )
    return earlier, [e for e in changed if e.scenario.scenario_id != "never/ran.xosc"], kept
