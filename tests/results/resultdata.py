"""Builders of result values for the results tests (imported as ``resultdata``)."""

from __future__ import annotations

import datetime
import hashlib

from simtest_operator import results
from simtest_operator.verdicts import ScenarioOutcome, Verdict

T0 = datetime.datetime(2025, 3, 1, 12, 0, tzinfo=datetime.UTC)


def scenario(
    name: str, *, category: str = "cut-in", content: str = "", **kwargs: object
) -> results.ScenarioInfo:
    """A scenario whose digest derives from its name (and optional content)."""
    digest = hashlib.sha256(f"{name}{content}".encode()).hexdigest()
    return results.ScenarioInfo(
        scenario_id=name,
        sha256=digest,
        source=f"file:///scenarios/{name}",
        category=category,
        **kwargs,  # type: ignore[arg-type]
    )


def outcome(name: str, verdict: Verdict = Verdict.PASSED, **kwargs: object) -> ScenarioOutcome:
    """An outcome for scenario ``name``."""
    return ScenarioOutcome(scenario_id=name, verdict=verdict, **kwargs)  # type: ignore[arg-type]


def campaign(name: str = "smoke", *, started_at: datetime.datetime = T0) -> results.CampaignInfo:
    """Campaign info with SUT and simulator versions."""
    return results.CampaignInfo(
        name=name,
        namespace="team-a",
        manifest_sha256="ab" * 32,
        started_at=started_at,
        sut_name="idm-driver",
        sut_version="1.4.0",
        simulator_version="sumo-1.20",
        settings={"parallel": 2, "stepLength": 0.05},
    )


def sample_run(
    *, run_key: str = "smoke-20250301T120000Z-0badcafe", finished: bool = True
) -> tuple[results.CampaignRecord, list[results.StoredOutcome], list[results.ScenarioInfo]]:
    """A small campaign with every verdict, a retried scenario and one scenario that never ran."""
    listed = [
        scenario("cut-in/close.xosc", tags=("highway", "cut-in"), road="A9.xodr"),
        scenario("cut-in/far.xosc", tags=("highway",), road="A9.xodr"),
        scenario("ped/crossing.xosc", category="pedestrian", tags=("urban",), road="town.xodr"),
        scenario(
            "ped/night.xosc", category="pedestrian", tags=("urban", "night"), road="town.xodr"
        ),
        scenario("follow/stop.xosc", category="car-following", road="A9.xodr"),
        scenario("broken/bad.xosc", category="car-following", road="missing.xodr"),
        scenario("skip/me.xosc", category="car-following"),
        scenario("never/ran.xosc", category="cut-in"),
    ]
    by_id = {s.scenario_id: s for s in listed}
    verdicts = [
        ("cut-in/close.xosc", Verdict.FAILED, "collision with 'cutter' at t=7.2 s", 1),
        ("cut-in/far.xosc", Verdict.PASSED, "", 1),
        ("ped/crossing.xosc", Verdict.PASSED, "", 1),
        ("ped/night.xosc", Verdict.TIMEOUT, "no verdict within 120 s wall time", 1),
        ("follow/stop.xosc", Verdict.ERROR, "simulator exited with code -9", 1),
        ("follow/stop.xosc", Verdict.PASSED, "", 2),
        ("broken/bad.xosc", Verdict.INVALID, "road network missing.xodr not found <LogicFile>", 1),
        ("skip/me.xosc", Verdict.SKIPPED, "campaign cancelled", 1),
    ]
    stored = [
        results.StoredOutcome(
            scenario=by_id[name],
            outcome=outcome(
                name,
                verdict,
                reason=reason,
                attempts=attempt,
                metrics={"minTTC": 0.4 if verdict is Verdict.FAILED else 3.2, "maxDecel": 4.5},
                simulated_seconds=20.0,
                wall_seconds=0.25,
                artifacts={"recording": f"{name}/recording.mcap", "result": f"{name}/result.json"},
                versions={"simulator": "sumo-1.20"},
            ),
            content_hashes={"scenario": by_id[name].sha256},
            recorded_at=T0,
        )
        for name, verdict, reason, attempt in verdicts
    ]
    record = results.CampaignRecord(
        run_key=results.RunKey(run_key),
        info=campaign(),
        finished_at=T0 + datetime.timedelta(seconds=42.5) if finished else None,
        phase="Failed" if finished else "",
    )
    return record, stored, listed
