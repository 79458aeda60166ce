"""History and flakiness: what a scenario did across every run in the database.

Works on the existing tables only (``runs`` joined with ``campaigns``): a run is the final
attempt of a scenario in one campaign run; the seed is the campaign's ``settings.seed``.

Flakiness is judged within a *family*: the same scenario content (id + sha256), SUT name and
version, and simulator version -- a verdict that changes with the SUT version is a regression
or a fix, not a flake. Within a family that both passed and failed (``Failed``/``Timeout``):

* ``nondeterministic`` -- the same seed gave different verdicts: the simulation does not repeat
  (simulator or rig nondeterminism; the recordings' digests differ too);
* ``seed-sensitive`` -- every seed repeated its verdict (run at least twice each) but seeds
  disagree: the system under test is unstable under the scenario's stochastic variation;
* ``unconfirmed`` -- verdicts differ but no seed was rerun: rerun with the same seed to tell.

Independently, ``retried`` marks a scenario that passed only on a later attempt: the pass is
shown with its earlier attempts, never silently counted as a clean one.
"""

from __future__ import annotations

import dataclasses
import datetime
import enum
from collections.abc import Iterable, Sequence
from typing import Any, cast

from simtest_operator.results.querying import ReadOnlyDatabase

FINAL_ATTEMPT = (
    "NOT EXISTS (SELECT 1 FROM runs later WHERE later.run_key = r.run_key "
    "AND later.scenario_id = r.scenario_id AND later.attempt > r.attempt)"
)
"""SQL condition keeping the final attempt of each (run, scenario) of ``runs r``."""
FAILING = ("Failed", "Timeout")
"""Verdicts on the system under test that count against a pass in a flakiness family."""


class Flakiness(enum.StrEnum):
    """How a scenario's verdicts behaved across runs (see the module docstring)."""

    STABLE = "stable"
    RETRIED = "retried"
    UNCONFIRMED = "unconfirmed"
    SEED_SENSITIVE = "seed-sensitive"
    NONDETERMINISTIC = "nondeterministic"

    @property
    def flaky(self) -> bool:
        """Whether a person should treat the scenario's verdict with suspicion."""
        return self is not Flakiness.STABLE

    @property
    def explanation(self) -> str:
        """One line for a person: what the flag means and what to do."""
        return _EXPLANATIONS[self]


_EXPLANATIONS = {
    Flakiness.STABLE: "same inputs always gave the same verdict",
    Flakiness.RETRIED: "passed only on a later attempt after an error",
    Flakiness.UNCONFIRMED: "verdicts differ for the same inputs; rerun with the same seed",
    Flakiness.SEED_SENSITIVE: "each seed repeats its verdict but seeds disagree: SUT instability",
    Flakiness.NONDETERMINISTIC: "the same seed gave different verdicts: simulation nondeterminism",
}
_SEVERITY = list(Flakiness)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Family:
    """Final verdicts of one scenario content under one SUT version, simulator and seed."""

    scenario_id: str
    sha256: str
    sut: str
    simulator: str
    seed: str | None
    runs: int
    passed: int
    failed: int
    recordings: int
    """Distinct recording digests (more than one for one seed: the simulation did not repeat)."""

    @property
    def mixed(self) -> bool:
        """Both passed and failed."""
        return self.passed > 0 and self.failed > 0


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Summary:
    """One scenario across every run: counts, dates, flakiness."""

    scenario_id: str
    runs: int
    passed: int
    failing: int
    first_failure: datetime.datetime | None
    last_pass: datetime.datetime | None
    last_run: datetime.datetime | None
    last_verdict: str
    retried_passes: int
    flakiness: Flakiness = Flakiness.STABLE

    @property
    def pass_rate(self) -> float:
        """Passed over runs (0 when none)."""
        return self.passed / self.runs if self.runs else 0.0


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Entry:
    """One run of one scenario, newest first in :class:`ScenarioHistory`."""

    run_key: str
    campaign: str
    started_at: datetime.datetime
    sut: str
    simulator: str
    seed: str | None
    attempt: int
    verdict: str
    reason: str
    sha256: str
    recording: str
    """The recording's sha256 (empty when none was stored)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ScenarioHistory:
    """Every run of one scenario with its summary and flakiness families."""

    summary: Summary
    entries: tuple[Entry, ...]
    families: tuple[Family, ...]


def classify(families: Iterable[Family], *, retried_passes: int = 0) -> Flakiness:
    """The flakiness of one scenario from its families (see the module docstring)."""
    by_inputs: dict[tuple[str, str, str], list[Family]] = {}
    for family in families:
        by_inputs.setdefault((family.sha256, family.sut, family.simulator), []).append(family)
    worst = Flakiness.RETRIED if retried_passes else Flakiness.STABLE
    for seeds in by_inputs.values():
        passed = sum(f.passed for f in seeds)
        failed = sum(f.failed for f in seeds)
        if not (passed and failed):
            continue
        if any(f.mixed and f.seed is not None for f in seeds):
            found = Flakiness.NONDETERMINISTIC
        elif all(f.seed is not None and f.runs >= 2 and not f.mixed for f in seeds):
            found = Flakiness.SEED_SENSITIVE
        else:
            found = Flakiness.UNCONFIRMED
        worst = max(worst, found, key=_SEVERITY.index)
    return worst


def _families_sql(db: ReadOnlyDatabase, where: str) -> str:
    seed = db.json_text("c.settings", "seed")
    recording = db.json_text("r.content_hashes", "recording")
    failing = ", ".join(f"'{v}'" for v in FAILING)
    return (
        f"SELECT r.scenario_id, r.sha256, c.sut_name || ' ' || c.sut_version, "
        f"c.simulator_version, {seed}, COUNT(*), "
        "SUM(CASE WHEN r.verdict = 'Passed' THEN 1 ELSE 0 END), "
        f"SUM(CASE WHEN r.verdict IN ({failing}) THEN 1 ELSE 0 END), "
        f"COUNT(DISTINCT {recording}) "
        f"FROM runs r JOIN campaigns c ON c.run_key = r.run_key WHERE {FINAL_ATTEMPT}{where} "
        f"GROUP BY r.scenario_id, r.sha256, c.sut_name, c.sut_version, c.simulator_version, {seed}"
    )


def _family(row: Sequence[Any]) -> Family:
    scenario_id, sha256, sut, simulator, seed, runs, passed, failed, recordings = row
    return Family(
        scenario_id=str(scenario_id),
        sha256=str(sha256),
        sut=str(sut).strip(),
        simulator=str(simulator),
        seed=None if seed is None else str(seed),
        runs=int(runs),
        passed=int(passed or 0),
        failed=int(failed or 0),
        recordings=int(recordings or 0),
    )


def _summaries_sql(where: str) -> str:
    failing = "r.verdict NOT IN ('Passed', 'Skipped')"
    return (
        "SELECT r.scenario_id, COUNT(*), "
        "SUM(CASE WHEN r.verdict = 'Passed' THEN 1 ELSE 0 END), "
        f"SUM(CASE WHEN {failing} THEN 1 ELSE 0 END), "
        f"MIN(CASE WHEN {failing} THEN c.started_at END), "
        "MAX(CASE WHEN r.verdict = 'Passed' THEN c.started_at END), MAX(c.started_at), "
        "SUM(CASE WHEN r.verdict = 'Passed' AND r.attempt > 1 THEN 1 ELSE 0 END) "
        f"FROM runs r JOIN campaigns c ON c.run_key = r.run_key WHERE {FINAL_ATTEMPT}{where} "
        "GROUP BY r.scenario_id"
    )


def summaries(
    db: ReadOnlyDatabase, *, scenario_ids: Sequence[str] | None = None
) -> tuple[Summary, ...]:
    """Every scenario's (or the given ones') summary, flaky first, then by scenario id."""
    where, params = "", cast(tuple[object, ...], ())
    if scenario_ids is not None:
        if not scenario_ids:
            return ()
        where = f" AND r.scenario_id IN ({', '.join('?' * len(scenario_ids))})"
        params = tuple(scenario_ids)
    families: dict[str, list[Family]] = {}
    for row in db.query(_families_sql(db, where), params):
        family = _family(row)
        families.setdefault(family.scenario_id, []).append(family)
    last = _last_verdicts(db, where, params)
    found = []
    for row in db.query(_summaries_sql(where), params):
        scenario_id, runs, passed, failing, first_failure, last_pass, last_run, retried = row
        found.append(
            Summary(
                scenario_id=str(scenario_id),
                runs=int(runs),
                passed=int(passed or 0),
                failing=int(failing or 0),
                first_failure=db.time(first_failure),
                last_pass=db.time(last_pass),
                last_run=db.time(last_run),
                last_verdict=last.get(str(scenario_id), ""),
                retried_passes=int(retried or 0),
                flakiness=classify(
                    families.get(str(scenario_id), ()), retried_passes=int(retried or 0)
                ),
            )
        )
    found.sort(key=lambda s: (-_SEVERITY.index(s.flakiness), s.scenario_id))
    return tuple(found)


def _last_verdicts(db: ReadOnlyDatabase, where: str, params: tuple[object, ...]) -> dict[str, str]:
    rows = db.query(
        "SELECT r.scenario_id, r.verdict FROM runs r JOIN campaigns c ON c.run_key = r.run_key "
        "JOIN (SELECT r.scenario_id AS sid, MAX(c.started_at) AS newest FROM runs r "
        f"JOIN campaigns c ON c.run_key = r.run_key WHERE 1 = 1{where} GROUP BY r.scenario_id) "
        f"n ON n.sid = r.scenario_id AND n.newest = c.started_at WHERE {FINAL_ATTEMPT}",
        params,
    )
    return {str(scenario_id): str(verdict) for scenario_id, verdict in rows}


def scenario_history(
    db: ReadOnlyDatabase, scenario_id: str, *, limit: int = 200
) -> ScenarioHistory:
    """The newest ``limit`` runs of one scenario, its summary and families (all runs)."""
    seed = db.json_text("c.settings", "seed")
    recording = db.json_text("r.content_hashes", "recording")
    rows = db.query(
        "SELECT r.run_key, c.name, c.started_at, c.sut_name || ' ' || c.sut_version, "
        f"c.simulator_version, {seed}, r.attempt, r.verdict, r.reason, r.sha256, {recording} "
        f"FROM runs r JOIN campaigns c ON c.run_key = r.run_key "
        f"WHERE r.scenario_id = ? AND {FINAL_ATTEMPT} "
        "ORDER BY c.started_at DESC, r.run_key DESC LIMIT ?",
        (scenario_id, limit),
    )
    entries = tuple(
        Entry(
            run_key=str(row[0]),
            campaign=str(row[1]),
            started_at=db.time(row[2]) or datetime.datetime.min.replace(tzinfo=datetime.UTC),
            sut=str(row[3]).strip(),
            simulator=str(row[4]),
            seed=None if row[5] is None else str(row[5]),
            attempt=int(row[6]),
            verdict=str(row[7]),
            reason=str(row[8]),
            sha256=str(row[9]),
            recording=str(row[10] or ""),
        )
        for row in rows
    )
    where = " AND r.scenario_id = ?"
    families = tuple(_family(row) for row in db.query(_families_sql(db, where), (scenario_id,)))
    found = summaries(db, scenario_ids=[scenario_id])
    summary = found[0] if found else Summary(
        scenario_id=scenario_id, runs=0, passed=0, failing=0, first_failure=None,
        last_pass=None, last_run=None, last_verdict="", retried_passes=0,
    )  # fmt: skip
    return ScenarioHistory(summary=summary, entries=entries, families=families)
