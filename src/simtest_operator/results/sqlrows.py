"""Rows to records: the column lists the shared queries select and their conversion.

Kept apart from :mod:`.sqlstore` (the queries) so each stays small; a :class:`Codec` supplies the
database-specific representation of JSON and timestamps.
"""

from __future__ import annotations

import datetime
from collections.abc import Mapping
from typing import Any, Protocol

from simtest_operator.results import records
from simtest_operator.verdicts import ScenarioOutcome, Verdict

Row = tuple[Any, ...]


class Codec(Protocol):
    """Database representation of JSON values and timestamps."""

    def json_in(self, value: object) -> object: ...

    def json_out(self, raw: Any) -> Any: ...

    def time_in(self, value: datetime.datetime) -> object: ...

    def time_out(self, raw: Any) -> datetime.datetime: ...


OUTCOME_COLUMNS = (
    "r.scenario_id, r.sha256, r.attempt, r.verdict, r.reason, r.simulated_seconds, "
    "r.wall_seconds, r.artifacts, r.content_hashes, r.versions, r.recorded_at, "
    "r.ignored_elements, s.source, s.tags, s.category, s.road"
)
CAMPAIGN_COLUMNS = (
    "run_key, name, namespace, manifest_sha256, started_at, finished_at, phase, sut_name, "
    "sut_version, simulator_version, settings, counts"
)


def campaign(codec: Codec, row: Row) -> records.CampaignRecord:
    """A ``campaigns`` row selected with :data:`CAMPAIGN_COLUMNS`."""
    return records.CampaignRecord(
        run_key=records.RunKey(row[0]),
        info=records.CampaignInfo(
            name=row[1],
            namespace=row[2],
            manifest_sha256=row[3],
            started_at=codec.time_out(row[4]),
            sut_name=row[7],
            sut_version=row[8],
            simulator_version=row[9],
            settings=codec.json_out(row[10]),
        ),
        finished_at=None if row[5] is None else codec.time_out(row[5]),
        phase=row[6],
        counts={str(k): int(v) for k, v in dict(codec.json_out(row[11]) or {}).items()},
    )


def scenario(
    codec: Codec, scenario_id: str, sha256: str, source: str, tags: Any, category: str, road: str
) -> records.ScenarioInfo:
    """A ``scenarios`` row (id, sha256, source, tags, category, road)."""
    return records.ScenarioInfo(
        scenario_id=scenario_id,
        sha256=sha256,
        source=source,
        tags=tuple(codec.json_out(tags)),
        category=category,
        road=road,
    )


def outcome(
    codec: Codec, row: Row, metrics: Mapping[tuple[str, int], Mapping[str, float]]
) -> records.StoredOutcome:
    """A ``runs`` row joined with its scenario (:data:`OUTCOME_COLUMNS`) plus its metrics."""
    (scenario_id, sha256, attempt, verdict, reason, simulated, wall, artifacts, hashes) = row[:9]
    versions, recorded_at, ignored, source, tags, category, road = row[9:]
    return records.StoredOutcome(
        scenario=scenario(codec, scenario_id, sha256, source, tags, category, road),
        outcome=ScenarioOutcome(
            scenario_id=scenario_id,
            verdict=Verdict(verdict),
            reason=reason,
            metrics=dict(metrics.get((scenario_id, int(attempt)), {})),
            simulated_seconds=float(simulated),
            wall_seconds=float(wall),
            attempts=int(attempt),
            artifacts=codec.json_out(artifacts),
            ignored_elements=tuple(codec.json_out(ignored)),
            versions=codec.json_out(versions),
        ),
        content_hashes=codec.json_out(hashes),
        recorded_at=codec.time_out(recorded_at),
    )
