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
    "NOT EXISTS (SELECT 1 FROM runs later WHERE later.attempt > 1 AND later.run_key = r.run_key "
    "AND later.scenario_id = r.scenario_id AND later.attempt > r.attempt)"
)
"""SQL condition keeping the final attempt of each (run, scenario) of ``runs r``. The redundant
``later.attempt > 1`` lets the planner hash only the few retried rows instead of every run
(PostgreSQL, 100,000 runs: about half the time of the whole history query)."""
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
    recordings: int | None = None
    """Distinct recording digests (more than one for one seed: the simulation did not repeat);
    counted for one scenario's history, ``None`` in the all-scenario summaries."""

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


def _cells_sql(db: ReadOnlyDatabase, where: str) -> str:
    """One scan for every summary: final attempts counted per family and verdict, with the
    first and last campaign start and the passes on a later attempt; Python folds the rest.

    Each campaign's family (SUT, simulator, seed) is numbered once in a subquery, so the scan
    groups by a small integer instead of extracting JSON and comparing text on every run row.
    """
    seed = db.json_text("settings", "seed")
    campaigns = (
        "SELECT run_key, started_at, sut_name || ' ' || sut_version AS sut, simulator_version "
        f"AS sim, {seed} AS seed, DENSE_RANK() OVER (ORDER BY sut_name, sut_version, "
        f"simulator_version, {seed}) AS family FROM campaigns"
    )
    return (
        "SELECT r.scenario_id, r.sha256, MIN(c.sut), MIN(c.sim), MIN(c.seed), r.verdict, "
        "COUNT(*), MIN(c.started_at), MAX(c.started_at), "
        "SUM(CASE WHEN r.attempt > 1 THEN 1 ELSE 0 END) "
        f"FROM runs r JOIN ({campaigns}) c ON c.run_key = r.run_key WHERE {FINAL_ATTEMPT}{where} "
        "GROUP BY r.scenario_id, r.sha256, c.family, r.verdict"
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
    families: dict[str, dict[tuple[str, str, str, str | None], list[int]]] = {}
    totals: dict[str, dict[str, Any]] = {}
    for row in db.query(_cells_sql(db, where), params):
        scenario_id, sha256, sut, simulator, seed, verdict, count, first, last, retried = row
        key = (str(sha256), str(sut).strip(), str(simulator), None if seed is None else str(seed))
        cell = families.setdefault(str(scenario_id), {}).setdefault(key, [0, 0, 0])
        cell[0] += int(count)
        cell[1] += int(count) if verdict == "Passed" else 0
        cell[2] += int(count) if verdict in FAILING else 0
        first_at, last_at = db.time(first), db.time(last)
        total = totals.setdefault(str(scenario_id), {"runs": 0, "passed": 0, "failing": 0,
                                                     "first_failure": None, "last_pass": None,
                                                     "last": (None, ""), "retried": 0})  # fmt: skip
        total["runs"] += int(count)
        if verdict == "Passed":
            total["passed"] += int(count)
            total["retried"] += int(retried or 0)
            total["last_pass"] = _latest(total["last_pass"], last_at)
        elif verdict != "Skipped":
            total["failing"] += int(count)
            total["first_failure"] = _earliest(total["first_failure"], first_at)
        if last_at is not None and (total["last"][0] is None or last_at > total["last"][0]):
            total["last"] = (last_at, str(verdict))
    found = []
    for scenario_id, total in totals.items():
        grouped = [
            Family(scenario_id=scenario_id, sha256=sha256, sut=sut, simulator=simulator,
                   seed=seed, runs=runs, passed=passed, failed=failed)
            for (sha256, sut, simulator, seed), (runs, passed, failed)
            in families[scenario_id].items()
        ]  # fmt: skip
        found.append(
            Summary(
                scenario_id=scenario_id,
                runs=total["runs"],
                passed=total["passed"],
                failing=total["failing"],
                first_failure=total["first_failure"],
                last_pass=total["last_pass"],
                last_run=total["last"][0],
                last_verdict=total["last"][1],
                retried_passes=total["retried"],
                flakiness=classify(grouped, retried_passes=total["retried"]),
            )
        )
    found.sort(key=lambda s: (-_SEVERITY.index(s.flakiness), s.scenario_id))
    return tuple(found)


def _earliest(a: datetime.datetime | None, b: datetime.datetime | None) -> datetime.datetime | None:
    return b if a is None else a if b is None else min(a, b)


def _latest(a: datetime.datetime | None, b: datetime.datetime | None) -> datetime.datetime | None:
    return b if a is None else a if b is None else max(a, b)


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
