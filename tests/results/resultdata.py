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
