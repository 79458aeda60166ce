"""Writing a local run into the results store: one campaign record, one row per attempt.

The store is a SQLite file in the output folder unless a DSN is given (``--db``, or the
campaign's ``spec.results.databaseSecretRef`` when the secret is available locally). A resumed
run reopens the same campaign record by its run key, and the store's per-attempt idempotency means
an attempt recorded twice is still one row.
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

from simtest_operator import provenance, results
from simtest_operator.errors import SourceError
from simtest_operator.runner import preparing
from simtest_operator.scenarios.pinned import PinnedScenario
from simtest_operator.scenarios.querying import SecretProvider
from simtest_operator.scenarios.specs import SecretRef
from simtest_operator.verdicts import ScenarioOutcome


@dataclasses.dataclass(slots=True, kw_only=True)
class ResultWriter:
    """An open store plus the run key and the scenario records of this run."""

    store: results.Store
    target: str | Path
    key: results.RunKey
    infos: dict[str, results.ScenarioInfo]
    info: results.CampaignInfo

    @property
    def run_key(self) -> str:
        """The run key as text."""
        return str(self.key)

    @property
    def description(self) -> str:
        """Where results go, without a password."""
        return results.describe(self.target)

    @classmethod
    @contextlib.contextmanager
    def open(
        cls,
        plan: preparing.Plan,
        *,
        database: str | None,
        secrets: SecretProvider | None,
        paths: Mapping[str, Path],
        now: Callable[[], datetime.datetime],
        parallel: int,
        notes: list[str],
    ) -> Iterator[ResultWriter]:
        """Open the store, begin (or resume) the campaign record; close it afterwards."""
        target = database or _secret_dsn(plan, secrets, notes) or plan.output.root
        plan.output.root.mkdir(parents=True, exist_ok=True)
        infos = {s.id: scenario_info(s, paths.get(s.id)) for s in plan.frozen.scenarios}
        sut = plan.spec.environment.sut
        info = results.CampaignInfo(
            name=plan.name,
            manifest_sha256=plan.manifest_sha256,
            started_at=plan.started_at,
            sut_name=sut.name,
            sut_version=sut.version,
            simulator_version=provenance.versions()["simulator"],
            settings={
                **preparing.describe_plan(plan),
                "parallel": parallel,
                "versions": dict(provenance.versions()),
            },
        )
        with results.open_store(target) as store:
            key = store.begin_campaign(
                info,
                scenarios=list(infos.values()),
                run_key=results.RunKey(plan.run_key) if plan.run_key else None,
            )
            yield cls(store=store, target=target, key=key, infos=infos, info=info)

    def register(self, pinned: PinnedScenario, path: Path) -> None:
        """A scenario that joined the frozen list while the run goes on (a search's proposal)."""
        self.infos[pinned.id] = scenario_info(pinned, path)

    def attempt(self, pinned: PinnedScenario, outcome: ScenarioOutcome) -> None:
        """Record one attempt (a retried Error, or the final one)."""
        self.store.add_outcome(self.key, self.infos[pinned.id], outcome)

    def finish(
        self,
        phase: str,
        *,
        finished_at: datetime.datetime,
        search: Mapping[str, Any] | None = None,
    ) -> None:
        """Mark the campaign record finished with its phase (Cancelled when interrupted); a
        search's record (proposals and summary) joins the campaign's settings."""
        info = None
        if search is not None:
            info = dataclasses.replace(self.info, settings={**self.info.settings, "search": search})
        self.store.finish_campaign(self.key, finished_at=finished_at, phase=phase, info=info)


def scenario_info(pinned: PinnedScenario, path: Path | None) -> results.ScenarioInfo:
    """The store's record of a frozen-list entry, with tags, category and road from its header."""
    tags, category, road = preparing.header_labels(path)
    return results.ScenarioInfo(
        scenario_id=pinned.id,
        source=pinned.source,
        sha256=pinned.sha256,
        tags=tags,
        category=category or results.UNCATEGORIZED,
        road=road,
    )


def _secret_dsn(
    plan: preparing.Plan, secrets: SecretProvider | None, notes: list[str]
) -> str | None:
    ref = plan.spec.results.database_secret_ref
    if ref is None:
        return None
    if secrets is not None:
        try:
            return secrets(SecretRef(name=ref.name, key=ref.key))
        except SourceError as exc:
            notes.append(f"results database: {exc}; using SQLite in the output folder instead")
            return None
    notes.append(
        f"results database secret {ref.name}/{ref.key} is not available locally; "
        "using SQLite in the output folder (give --db DSN to use PostgreSQL)"
    )
    return None
