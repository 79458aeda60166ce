"""The output folder of a local campaign run: one layout, written so that it is always consistent.

::

    <out>/manifest.yaml        the manifest as read (a rerun needs nothing else)
    <out>/frozen.json          the frozen scenario list (``--frozen`` takes it back)
    <out>/campaign.json        state (running/interrupted/finished/failed), counts, store, run key
    <out>/results.sqlite       the results database (unless a DSN was given)
    <out>/junit.xml            JUnit XML for CI
    <out>/report.html          the HTML report
    <out>/scenarios/<safe id>/{result.json, log.txt, recording.mcap, ...}

Every file is written to a temporary name and renamed into place, so a run killed at any moment
leaves either the old or the new version, never half a file. A scenario counts as finished when
its ``result.json`` holds a final verdict other than ``Skipped``; that is what a resumed run skips.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import re
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from simtest_operator.errors import ScenarioError
from simtest_operator.runner import tasks
from simtest_operator.scenarios.pinned import FrozenList, PinnedScenario
from simtest_operator.verdicts import ScenarioOutcome, Verdict

MANIFEST = "manifest.yaml"
FROZEN = "frozen.json"
STATE = "campaign.json"
JUNIT = "junit.xml"
REPORT = "report.html"
SCENARIOS = "scenarios"

_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


def safe_name(scenario_id: str) -> str:
    """A folder name for ``scenario_id``: readable, filesystem-safe and unique (hash suffix)."""
    readable = _UNSAFE.sub("_", scenario_id.replace("/", "__")).strip("._")[:96] or "scenario"
    return f"{readable}-{hashlib.sha256(scenario_id.encode()).hexdigest()[:8]}"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RunState:
    """``campaign.json``: what a later ``simtest run`` needs to resume or rerun."""

    campaign: str
    manifest_sha256: str
    state: str
    """``running``, ``interrupted``, ``finished`` or ``failed`` (the run stopped on an error
    outside any scenario, e.g. an unreachable results database; ``reason`` says which)."""
    started_at: str
    finished_at: str = ""
    run_key: str = ""
    store: str = ""
    """Where results went (a path, or a DSN without its password)."""
    parallel: int = 0
    counts: Mapping[str, int] = dataclasses.field(default_factory=dict)
    wall_seconds: float = 0.0
    exit_code: int | None = None
    reason: str = ""

    def to_json(self) -> dict[str, Any]:
        """JSON form (camelCase)."""
        return {
            "campaign": self.campaign,
            "manifestSha256": self.manifest_sha256,
            "state": self.state,
            "startedAt": self.started_at,
            "finishedAt": self.finished_at,
            "runKey": self.run_key,
            "store": self.store,
            "parallel": self.parallel,
            "counts": dict(self.counts),
            "wallSeconds": round(self.wall_seconds, 3),
            "exitCode": self.exit_code,
            "reason": self.reason,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> RunState:
        """Inverse of :meth:`to_json`."""
        return cls(
            campaign=str(data.get("campaign", "")),
            manifest_sha256=str(data.get("manifestSha256", "")),
            state=str(data.get("state", "")),
            started_at=str(data.get("startedAt", "")),
            finished_at=str(data.get("finishedAt", "")),
            run_key=str(data.get("runKey", "")),
            store=str(data.get("store", "")),
            parallel=int(data.get("parallel", 0)),
            counts={str(k): int(v) for k, v in dict(data.get("counts", {})).items()},
            wall_seconds=float(data.get("wallSeconds", 0.0)),
            exit_code=data.get("exitCode"),
            reason=str(data.get("reason", "")),
        )


@dataclasses.dataclass(frozen=True, slots=True)
class OutputDir:
    """Reads and writes one run's output folder."""

    root: Path

    def scenario_dir(self, scenario_id: str) -> Path:
        """The folder of one scenario's artifacts."""
        return self.root / SCENARIOS / safe_name(scenario_id)

    @property
    def manifest(self) -> Path:
        return self.root / MANIFEST

    @property
    def frozen(self) -> Path:
        return self.root / FROZEN

    @property
    def state(self) -> Path:
        return self.root / STATE

    @property
    def junit(self) -> Path:
        return self.root / JUNIT

    @property
    def report(self) -> Path:
        return self.root / REPORT

    def exists(self) -> bool:
        """Whether a run already wrote here."""
        return self.state.is_file()

    def write_text(self, path: Path, text: str) -> None:
        """Atomically replace ``path`` with ``text``."""
        path.parent.mkdir(parents=True, exist_ok=True)
        handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
        try:
            with os.fdopen(handle, "w", encoding="utf-8") as sink:
                sink.write(text)
            Path(temporary).replace(path)
        except BaseException:
            Path(temporary).unlink(missing_ok=True)
            raise

    def write_json(self, path: Path, document: Any) -> None:
        """Atomically write ``document`` as indented JSON."""
        self.write_text(path, json.dumps(document, indent=2, sort_keys=False) + "\n")

    def read_json(self, path: Path) -> Any:
        """Parse a JSON file of this folder; ScenarioError naming it when unreadable."""
        try:
            return json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise ScenarioError(f"cannot read {path}: {exc}") from exc

    def write_state(self, state: RunState) -> None:
        self.write_json(self.state, state.to_json())

    def read_state(self) -> RunState:
        return RunState.from_json(self.read_json(self.state))

    def write_frozen(self, frozen: FrozenList) -> None:
        self.write_json(self.frozen, frozen.to_json())

    def read_frozen(self) -> FrozenList:
        return FrozenList.from_json(self.read_json(self.frozen), where=str(self.frozen))

    def write_result(
        self,
        pinned: PinnedScenario,
        batch: int,
        outcome: ScenarioOutcome,
        *,
        timing: Mapping[str, object] | None = None,
    ) -> Path:
        """Write a scenario's final ``result.json`` (outcome plus what was run, and when: the
        final attempt's start and end on its worker process, for timelines)."""
        folder = self.scenario_dir(pinned.id)
        path = folder / tasks.RESULT
        engine_document = self._engine_result(path)
        document = {
            **engine_document,
            **outcome.to_json(),
            "batch": batch,
            "source": pinned.source,
            "sha256": pinned.sha256,
            "overrides": dict(pinned.overrides),
        }
        if timing is not None:
            document["timing"] = dict(timing)
        self.write_json(path, document)
        return path

    def _engine_result(self, path: Path) -> dict[str, Any]:
        """What the engine wrote into the result file of this attempt (extra detail such as
        trajectories is kept; the executor's fields win)."""
        try:
            document = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return {}
        return document if isinstance(document, dict) else {}

    def read_results(self, frozen: FrozenList) -> dict[str, ScenarioOutcome]:
        """The outcomes already written for the scenarios of ``frozen`` (unreadable ones skipped,
        so a half-deleted folder only means those scenarios run again)."""
        found: dict[str, ScenarioOutcome] = {}
        for pinned in frozen.scenarios:
            path = self.scenario_dir(pinned.id) / tasks.RESULT
            if not path.is_file():
                continue
            try:
                document = json.loads(path.read_text(encoding="utf-8"))
                outcome = ScenarioOutcome.from_json(document)
            except (OSError, ValueError, KeyError, TypeError):
                continue
            if outcome.scenario_id == pinned.id and document.get("sha256") == pinned.sha256:
                found[pinned.id] = outcome
        return found


def finished_ids(results: Mapping[str, ScenarioOutcome]) -> frozenset[str]:
    """The scenarios whose stored verdict is final (not Skipped)."""
    return frozenset(key for key, out in results.items() if out.verdict is not Verdict.SKIPPED)
