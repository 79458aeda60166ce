"""Delivering a simulator pod's results: artifacts to their store, attempts to the results database.

After the scenarios of a pod have run, each attempt leaves a folder (recording, log, result file)
and an outcome. Delivery, in this order per scenario:

1. **Artifacts.** With an ``s3://`` artifacts URI the files are uploaded (recording and log first,
   then the result file rewritten with the final URIs and uploaded last) and reported as
   ``s3://bucket/<prefix>/<campaign>/<environment>/<scenario>/<file>``. A file that cannot be
   uploaded keeps its local path and the reason says so; the verdict never changes. Otherwise
   local paths are reported under the run spec's URI prefix (``pvc://...``), as before.
2. **Results database.** With a DSN and a run key, the attempt is recorded through
   :func:`simtest_operator.results.record_pod_attempt` -- the same store code ``simtest run`` uses,
   idempotent per (run, scenario, attempt). A database that is down costs the row, not the verdict:
   the scenario is listed in :attr:`Delivered.unstored` and the termination message says
   ``resultsStored: false``.

With ``keep_recordings`` off (``spec.artifacts.keepRecordings: false``) each recording is deleted
first -- after the run computed its metrics and after its digest was taken for the results row --
so it is neither uploaded nor reported (no ``recording`` URI, also not in ``result.json``).

Everything respects the pod's deadline (``remaining``): no upload or connection starts without the
time to finish, so delivery can never turn a verdict into a deadline ``Timeout``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime
import hashlib
import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

from simtest_operator import results
from simtest_operator.errors import ResultsError
from simtest_operator.results.uploading import Uploader
from simtest_operator.runner import storing
from simtest_operator.scenarios import PinnedScenario
from simtest_operator.verdicts import ScenarioOutcome

RECORDING_FILE = "recording.mcap"
MIN_DB_SECONDS = 5.0
"""A database write is not started with less time than this before the deadline."""
CONNECT_TIMEOUT_SECONDS = 5

OpenStore = Callable[[str], results.Store]


def _open_store(dsn: str) -> results.Store:
    return results.open_store(dsn, connect_timeout=CONNECT_TIMEOUT_SECONDS)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ResultsTarget:
    """Where the pod's attempts go: a DSN (from the campaign's Secret) and the run key."""

    dsn: str = dataclasses.field(repr=False)
    run_key: results.RunKey


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Attempt:
    """One scenario the pod ran: its frozen entry, the located file and the outcome."""

    scenario: PinnedScenario
    path: Path | None
    """The scenario file as run (None when it could not be fetched)."""
    outcome: ScenarioOutcome
    """Artifacts as local paths; ``attempts`` is the pod's attempt number."""
    folder: Path
    """The scenario's artifacts folder."""
    stopped: bool = False
    """SIGTERM ended the pod before this scenario finished: the environment's verdict."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Delivered:
    """The outcomes as reported (final URIs) and what could not be stored."""

    outcomes: tuple[ScenarioOutcome, ...]
    unstored: frozenset[str] = frozenset()
    """Scenario ids whose row the results database did not take."""
    notes: tuple[str, ...] = ()
    """One line per problem, for the pod's log (no secrets)."""


@dataclasses.dataclass(slots=True, kw_only=True)
class Deliverer:
    """Delivers the attempts of one pod."""

    campaign: str
    artifacts_root: Path
    """The pod's artifacts folder (the run spec's ``artifactsDir``)."""
    uri_prefix: str = ""
    """The run spec's ``artifactsUri``: ``s3://...`` uploads, anything else prefixes paths."""
    uploader: Uploader | None = None
    results_target: ResultsTarget | None = None
    sut: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """SUT name and version (wire form) for a provisional run record."""
    now: Callable[[], datetime.datetime] = lambda: datetime.datetime.now(datetime.UTC)
    remaining: Callable[[], float] | None = None
    """Seconds left before the pod's deadline (None: unlimited)."""
    upload_problem: str | None = None
    """Why artifacts cannot be uploaded although the URI says ``s3://`` (e.g. no credentials)."""
    results_problem: str | None = None
    """Why attempts cannot be stored although a database is configured (e.g. no run key)."""
    open_store: OpenStore = _open_store
    keep_recordings: bool = True
    """False: recordings are dropped before delivery (their digest is still recorded)."""

    def deliver(self, attempts: Sequence[Attempt]) -> Delivered:
        """Deliver every attempt; never raises for storage problems."""
        notes: list[str] = []
        hashes = [content_hashes(a) for a in attempts]  # before a recording is dropped
        if not self.keep_recordings:
            attempts = [drop_recording(a, notes) for a in attempts]
        outcomes = [self._artifacts(a, notes) for a in attempts]
        unstored: set[str] = set()
        if self.results_problem is not None:
            unstored = {o.scenario_id for o in outcomes}
            notes.append(f"results not stored: {self.results_problem}")
        elif self.results_target is not None:
            unstored = self._store(attempts, outcomes, hashes, notes)
        return Delivered(outcomes=tuple(outcomes), unstored=frozenset(unstored), notes=tuple(notes))

    # --- artifacts -------------------------------------------------------------------------

    def _relative(self, path: str) -> str | None:
        root = str(self.artifacts_root)
        if path == root or not path.startswith(root + "/"):
            return None
        return path[len(root) + 1 :]

    def _artifacts(self, attempt: Attempt, notes: list[str]) -> ScenarioOutcome:
        outcome = attempt.outcome
        if self.upload_problem is not None:
            notes.append(f"{outcome.scenario_id}: artifacts not uploaded: {self.upload_problem}")
            return _with_note(outcome, sorted(outcome.artifacts))
        if self.uploader is None:
            return dataclasses.replace(outcome, artifacts=self._prefixed(outcome.artifacts))
        uploader = self.uploader
        uris: dict[str, str] = {}
        failed: list[str] = []
        for name, path in outcome.artifacts.items():
            if name == "result":
                continue
            relative = self._relative(path)
            if relative is None:
                uris[name] = path
                continue
            try:
                uris[name] = uploader.upload(Path(path), relative)
            except ResultsError as exc:
                uris[name] = path
                failed.append(name)
                notes.append(f"{outcome.scenario_id}: {exc}")
        result_path = outcome.artifacts.get("result")
        relative = self._relative(result_path) if result_path else None
        if result_path and relative is not None:
            uris["result"] = uploader.location.uri(relative)
            final = _with_note(dataclasses.replace(outcome, artifacts=uris), failed)
            try:
                _rewrite_result(Path(result_path), final)
                uploader.upload(Path(result_path), relative)
            except (ResultsError, OSError) as exc:
                uris["result"] = result_path
                failed.append("result")
                notes.append(f"{outcome.scenario_id}: {exc}")
                final = _with_note(dataclasses.replace(outcome, artifacts=uris), failed)
                with contextlib.suppress(OSError):  # the local copy tells the truth again
                    _rewrite_result(Path(result_path), final)
                return final
        elif result_path:
            uris["result"] = result_path
        return _with_note(dataclasses.replace(outcome, artifacts=uris), failed)

    def _prefixed(self, artifacts: Mapping[str, str]) -> dict[str, str]:
        if not self.uri_prefix:
            return dict(artifacts)
        out = {}
        for name, path in artifacts.items():
            relative = self._relative(path)
            out[name] = f"{self.uri_prefix}/{relative}" if relative is not None else path
        return out

    # --- results database ------------------------------------------------------------------

    def _store(
        self,
        attempts: Sequence[Attempt],
        outcomes: Sequence[ScenarioOutcome],
        hashes: Sequence[Mapping[str, str]],
        notes: list[str],
    ) -> set[str]:
        target = self.results_target
        assert target is not None
        ids = {o.scenario_id for o in outcomes}
        if self.remaining is not None and self.remaining() < MIN_DB_SECONDS:
            notes.append("results not stored: no time left before the pod's deadline")
            return ids
        try:
            store = self.open_store(target.dsn)
        except ResultsError as exc:
            notes.append(f"results not stored: {exc}")
            return ids
        unstored: set[str] = set()
        with store:
            for attempt, outcome, digests in zip(attempts, outcomes, hashes, strict=True):
                try:
                    results.record_pod_attempt(
                        store,
                        target.run_key,
                        campaign=self.campaign,
                        scenario=storing.scenario_info(attempt.scenario, attempt.path),
                        outcome=outcome,
                        content_hashes=digests,
                        now=self.now(),
                        sut_name=str(self.sut.get("name", "")),
                        sut_version=str(self.sut.get("version", "")),
                    )
                except ResultsError as exc:
                    unstored.add(outcome.scenario_id)
                    notes.append(f"{outcome.scenario_id}: result not stored: {exc}")
        return unstored


def drop_recording(attempt: Attempt, notes: list[str]) -> Attempt:
    """The attempt without its recording: the file deleted, its URI gone from the outcome and
    from the local ``result.json``."""
    outcome = attempt.outcome
    paths = {attempt.folder / RECORDING_FILE}
    if "recording" in outcome.artifacts:
        paths.add(Path(outcome.artifacts["recording"]))
    for path in paths:
        try:
            path.unlink(missing_ok=True)
        except OSError as exc:
            notes.append(f"{outcome.scenario_id}: recording not deleted: {exc.strerror or exc}")
    if "recording" not in outcome.artifacts:
        return attempt
    artifacts = {k: v for k, v in outcome.artifacts.items() if k != "recording"}
    outcome = dataclasses.replace(outcome, artifacts=artifacts)
    result = artifacts.get("result")
    if result:
        with contextlib.suppress(OSError):
            _rewrite_result(Path(result), outcome)
    return dataclasses.replace(attempt, outcome=outcome)


def content_hashes(attempt: Attempt) -> dict[str, str]:
    """sha256 of the scenario (pinned) and of the recording, when there is one."""
    hashes = {"scenario": attempt.scenario.sha256}
    recording = attempt.folder / RECORDING_FILE
    if recording.is_file():
        hashes["recording"] = _sha256(recording)
    return hashes


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for chunk in iter(lambda: handle.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def _with_note(outcome: ScenarioOutcome, failed: Sequence[str]) -> ScenarioOutcome:
    if not failed:
        return outcome
    note = f"artifacts kept on the pod's volume, upload failed: {', '.join(failed)}"
    reason = f"{outcome.reason}; {note}" if outcome.reason else note
    return dataclasses.replace(outcome, reason=reason)


def _rewrite_result(path: Path, outcome: ScenarioOutcome) -> None:
    """The full result file with the URIs it will be found under."""
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        document = {}
    document.update(outcome.to_json())
    path.write_text(json.dumps(document, indent=2, sort_keys=True) + "\n", encoding="utf-8")
