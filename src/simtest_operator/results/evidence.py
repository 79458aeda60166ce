"""Evidence bundles: one campaign run's verdicts with the inputs and outputs that back them.

A bundle is a folder a safety assessor can archive and check offline::

    manifest.json          campaign, SUT, simulator, per scenario: verdict, requirements and the
                           sha256 of every item (scenario, map, recording, verdict, metrics)
    manifest.sha256        the manifest's own digest (compare it with the one export printed)
    environment/sut.json, environment/simulator.json
    scenarios/<id>/scenario.xosc, map.xodr, recording.mcap, verdict.json, metrics.json

Items the exporter cannot reach (an ``s3://`` recording, a scenario fetched from git) are listed
with the digest the database recorded at run time and ``"included": false``, so the bundle still
names exactly what ran. :func:`verify` recomputes every digest, checks each against the one
recorded at run time (the scenario's pinned sha256, the recording's ``content_hashes``), and
refuses unlisted files. Requirements are the scenario's tags with the ``req:`` prefix (from the
FileHeader ``simtest:tags``), e.g. ``req:UN-R157-5.2.5.2``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import os
import re
import shutil
import stat
import urllib.parse
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path, PurePosixPath
from typing import Any, BinaryIO

from simtest_operator.errors import ResultsError
from simtest_operator.results import details
from simtest_operator.results.querying import ReadOnlyDatabase

FORMAT = "simtest-evidence/1"
MANIFEST = "manifest.json"
MANIFEST_DIGEST = "manifest.sha256"
REQUIREMENT_PREFIX = "req:"
"""Tags starting with this name a requirement or regulation clause the scenario evidences."""


def requirements(tags: Iterable[str]) -> tuple[str, ...]:
    """The requirement references among a scenario's tags, without the prefix, sorted."""
    return tuple(sorted({t[len(REQUIREMENT_PREFIX) :] for t in tags if _is_requirement(t)}))


def _is_requirement(tag: str) -> bool:
    return tag.startswith(REQUIREMENT_PREFIX) and len(tag) > len(REQUIREMENT_PREFIX)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Exported:
    """What :func:`export` wrote."""

    path: Path
    manifest_sha256: str
    scenarios: int
    files: int
    missing: tuple[str, ...]
    """Items named by digest only (not reachable from here), as ``<scenario>: <item> (why)``."""


def sha256_file(path: Path) -> str:
    """Hex sha256 of a file, read in chunks."""
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for chunk in iter(lambda: handle.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def _canonical(value: object) -> bytes:
    return (json.dumps(value, sort_keys=True, indent=2, allow_nan=False) + "\n").encode()


def _slug(scenario_id: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", scenario_id).strip("._") or "scenario"


def _local(uri: str, base: Path | None) -> Path | None:
    if not uri:
        return None
    parsed = urllib.parse.urlparse(uri)
    if parsed.scheme not in ("", "file") and len(parsed.scheme) > 1:
        return None
    return details.artifact_path(uri, base or Path.cwd())


class _Writer:
    """Writes bundle files and remembers their digests."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.files: dict[str, str] = {}

    def data(self, relative: str, value: object) -> dict[str, Any]:
        content = _canonical(value)
        target = self.root / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(content)
        self.files[relative] = hashlib.sha256(content).hexdigest()
        return {"path": relative, "sha256": self.files[relative], "included": True}

    def copy(self, relative: str, source: Path) -> dict[str, Any]:
        target = self.root / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(source, target)
        self.files[relative] = sha256_file(target)
        return {"path": relative, "sha256": self.files[relative], "included": True}


def export(
    db: ReadOnlyDatabase, run_key: str, out: Path, *, base_dir: Path | None = None
) -> Exported:
    """Write the bundle of run ``run_key`` to the new folder ``out``."""
    campaign = _campaign(db, run_key)
    if out.exists() and any(out.iterdir()):
        raise ResultsError(f"evidence folder {out} exists and is not empty")
    out.mkdir(parents=True, exist_ok=True)
    writer = _Writer(out)
    sut = writer.data("environment/sut.json", {"name": campaign["sut_name"],
                                               "version": campaign["sut_version"]})  # fmt: skip
    missing: list[str] = []
    entries = []
    outcomes = _final_outcomes(db, run_key)
    simulator_versions: dict[str, str] = {}
    for outcome in outcomes:
        simulator_versions.update(outcome["versions"])
        entries.append(_scenario_entry(writer, outcome, base_dir, missing))
    simulator = writer.data(
        "environment/simulator.json",
        {"version": campaign["simulator_version"], "versions": simulator_versions},
    )
    manifest = {
        "format": FORMAT,
        "campaign": {
            key: campaign[key]
            for key in (
                "run_key",
                "name",
                "namespace",
                "manifest_sha256",
                "started_at",
                "finished_at",
                "phase",
            )
        },
        "sut": sut,
        "simulator": simulator,
        "scenarios": entries,
        "files": dict(sorted(writer.files.items())),
    }
    content = _canonical(manifest)
    (out / MANIFEST).write_bytes(content)
    digest = hashlib.sha256(content).hexdigest()
    (out / MANIFEST_DIGEST).write_text(f"{digest}  {MANIFEST}\n", encoding="utf-8")
    return Exported(path=out, manifest_sha256=digest, scenarios=len(entries),
                    files=len(writer.files), missing=tuple(missing))  # fmt: skip


def _scenario_entry(
    writer: _Writer, outcome: Mapping[str, Any], base: Path | None, missing: list[str]
) -> dict[str, Any]:
    scenario_id = outcome["scenario_id"]
    folder = f"scenarios/{_slug(scenario_id)}"
    items: dict[str, dict[str, Any]] = {}

    def absent(item: str, recorded: str, why: str) -> None:
        items[item] = {"sha256": recorded, "included": False, "why": why}
        missing.append(f"{scenario_id}: {item} ({why})")

    pinned = outcome["sha256"]
    source = _local(outcome["source"], base)
    if source is None or not source.is_file():
        absent("scenario", pinned, f"source {outcome['source'] or '(unknown)'} not reachable")
    elif sha256_file(source) != pinned:
        absent("scenario", pinned, f"{source} changed since the run")
    else:
        items["scenario"] = writer.copy(f"{folder}/scenario{source.suffix}", source)
        items["scenario"]["recorded_sha256"] = pinned
        road = outcome["road"]
        map_file = source.parent / road if road else None
        if map_file is not None and map_file.is_file():
            items["map"] = writer.copy(f"{folder}/map{map_file.suffix}", map_file)
        elif road:
            absent("map", "", f"road network {road} not found beside the scenario")
    recorded = str(outcome["content_hashes"].get("recording", ""))
    recording = _local(outcome["artifacts"].get("recording", ""), base)
    if recording is not None and recording.is_file():
        items["recording"] = writer.copy(f"{folder}/recording.mcap", recording)
        if recorded:
            items["recording"]["recorded_sha256"] = recorded
    elif recorded or outcome["artifacts"].get("recording"):
        absent("recording", recorded, f"{outcome['artifacts'].get('recording', 'not kept')} "
               "not reachable")  # fmt: skip
    items["verdict"] = writer.data(f"{folder}/verdict.json", {
        "scenario_id": scenario_id, "verdict": outcome["verdict"], "reason": outcome["reason"],
        "attempt": outcome["attempt"], "earlier_attempts": outcome["earlier"],
        "simulated_seconds": outcome["simulated_seconds"],
        "wall_seconds": outcome["wall_seconds"], "versions": outcome["versions"],
        "requirements": list(requirements(outcome["tags"])),
    })  # fmt: skip
    items["metrics"] = writer.data(f"{folder}/metrics.json", outcome["metrics"])
    return {
        "id": scenario_id,
        "verdict": outcome["verdict"],
        "requirements": list(requirements(outcome["tags"])),
        "tags": list(outcome["tags"]),
        "items": items,
    }


def _campaign(db: ReadOnlyDatabase, run_key: str) -> dict[str, Any]:
    rows = db.query(
        "SELECT run_key, name, namespace, manifest_sha256, started_at, finished_at, phase, "
        "sut_name, sut_version, simulator_version FROM campaigns WHERE run_key = ?",
        (run_key,),
    )
    if not rows:
        raise ResultsError(f"no campaign run {run_key!r} in {db.where}")
    row = rows[0]
    started, finished = db.time(row[4]), db.time(row[5])
    return {
        "run_key": row[0], "name": row[1], "namespace": row[2], "manifest_sha256": row[3],
        "started_at": started.isoformat() if started else None,
        "finished_at": finished.isoformat() if finished else None,
        "phase": row[6], "sut_name": row[7], "sut_version": row[8], "simulator_version": row[9],
    }  # fmt: skip


def _final_outcomes(db: ReadOnlyDatabase, run_key: str) -> list[dict[str, Any]]:
    rows = db.query(
        "SELECT r.scenario_id, r.sha256, r.attempt, r.verdict, r.reason, r.simulated_seconds, "
        "r.wall_seconds, r.artifacts, r.content_hashes, r.versions, s.source, s.tags, s.road "
        "FROM runs r JOIN scenarios s ON s.scenario_id = r.scenario_id AND s.sha256 = r.sha256 "
        "WHERE r.run_key = ? ORDER BY r.scenario_id, r.attempt",
        (run_key,),
    )
    metrics: dict[tuple[str, int], dict[str, float | None]] = {}
    for scenario_id, attempt, name, value in db.query(
        "SELECT scenario_id, attempt, name, value FROM metrics WHERE run_key = ?", (run_key,)
    ):
        finite = value is not None and abs(float(value)) != float("inf")
        metrics.setdefault((scenario_id, int(attempt)), {})[name] = float(value) if finite else None
    final: dict[str, dict[str, Any]] = {}
    earlier: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        scenario_id = str(row[0])
        if scenario_id in final:
            previous = final[scenario_id]
            earlier.setdefault(scenario_id, []).append(
                {
                    "attempt": previous["attempt"],
                    "verdict": previous["verdict"],
                    "reason": previous["reason"],
                }
            )
        final[scenario_id] = {
            "scenario_id": scenario_id, "sha256": row[1], "attempt": int(row[2]),
            "verdict": row[3], "reason": row[4], "simulated_seconds": float(row[5]),
            "wall_seconds": float(row[6]), "artifacts": db.json(row[7]),
            "content_hashes": db.json(row[8]), "versions": db.json(row[9]), "source": row[10],
            "tags": tuple(db.json(row[11])), "road": row[12],
            "metrics": dict(sorted(metrics.get((scenario_id, int(row[2])), {}).items())),
        }  # fmt: skip
    for scenario_id, entry in final.items():
        entry["earlier"] = earlier.get(scenario_id, [])
    return [final[key] for key in sorted(final)]


def verify(bundle: Path) -> tuple[str, tuple[str, ...]]:
    """Recompute every digest of ``bundle``: (manifest sha256, problems); no problems = valid.

    A bundle holds regular files only: a symbolic link is refused even when its target has the
    listed digest (the target lies outside what was archived and may change after the check),
    and so are FIFOs and devices (reading one would hang)."""
    manifest_path = bundle / MANIFEST
    if (why := _not_regular(bundle, MANIFEST)) is not None:
        raise ResultsError(
            f"{bundle} is not an evidence bundle: "
            + (f"no {MANIFEST}" if why == "missing" else f"{MANIFEST} {why}")
        )
    content = _read_regular(manifest_path)
    digest = hashlib.sha256(content).hexdigest()
    files, scenarios = _parse_manifest(content, manifest_path)
    found: dict[str, str] = {}
    if (why := _not_regular(bundle, MANIFEST_DIGEST)) is None:
        stated = _read_regular(bundle / MANIFEST_DIGEST).decode("utf-8", errors="replace")
        if stated.split()[:1] != [digest]:
            found[MANIFEST_DIGEST] = f"{MANIFEST}: digest {digest} differs from {MANIFEST_DIGEST}"
    elif why != "missing":
        found[MANIFEST_DIGEST] = f"{MANIFEST_DIGEST}: {why}"
    verified: set[str] = set()
    for relative, expected in sorted(files.items()):
        if (why := _not_regular(bundle, relative)) is not None:
            found[relative] = f"{relative}: {why}"
        elif (actual := _sha256_regular(bundle / relative)) != expected:
            found[relative] = f"{relative}: sha256 {actual}, manifest says {expected}"
        else:
            verified.add(relative)
    for relative, why in _entries(bundle):
        if relative not in found and relative not in (MANIFEST, MANIFEST_DIGEST):
            if why is not None:
                found[relative] = f"{relative}: {why}"
            elif relative not in files:
                found[relative] = f"{relative}: not listed in the manifest"
    problems = list(found.values())
    for entry in scenarios:
        problems += _check_scenario(bundle, entry, files, verified)
    return digest, tuple(problems)


def _parse_manifest(content: bytes, where: Path) -> tuple[dict[str, str], list[dict[str, Any]]]:
    """The manifest's file list and scenario entries; ResultsError (one line) when it
    is not JSON of the expected shape -- deep nesting included (a 100,000-deep document was a
    RecursionError traceback)."""
    try:
        manifest = json.loads(content)
    except (ValueError, RecursionError) as exc:
        raise ResultsError(f"{where}: not a {FORMAT} manifest ({_short(exc)})") from None
    if not isinstance(manifest, dict):
        raise ResultsError(f"{where}: not a {FORMAT} manifest (not a JSON object)")
    if manifest.get("format") != FORMAT:
        raise ResultsError(f"{where}: format {_short(manifest.get('format'))!r}, not {FORMAT}")
    files, scenarios = manifest.get("files"), manifest.get("scenarios")
    shaped = (
        isinstance(files, dict)
        and all(isinstance(v, str) for v in files.values())
        and isinstance(scenarios, list)
        and all(
            isinstance(entry, dict)
            and isinstance(entry.get("items", {}), dict)
            and all(isinstance(item, dict) for item in entry.get("items", {}).values())
            for entry in scenarios
        )
    )
    if not shaped:
        raise ResultsError(
            f"{where}: not a {FORMAT} manifest ('files' must map paths to digests, 'scenarios' "
            "must be a list of objects whose 'items' are objects)"
        )
    assert isinstance(files, dict) and isinstance(scenarios, list)
    return files, scenarios


def _not_regular(bundle: Path, relative: str) -> str | None:
    """Why ``relative`` is not a regular file inside ``bundle`` reached without links, or None."""
    parts = PurePosixPath(relative).parts
    if not parts or ".." in parts or PurePosixPath(relative).is_absolute():
        return "path leaves the bundle"
    path = bundle
    for index, part in enumerate(parts):
        path = path / part
        try:
            mode = path.lstat().st_mode
        except OSError:
            return "missing"
        if stat.S_ISLNK(mode):
            return "is a symbolic link (a bundle holds regular files only)"
        if index < len(parts) - 1 and not stat.S_ISDIR(mode):
            return "missing"
    return None if stat.S_ISREG(mode) else "is not a regular file"


@contextlib.contextmanager
def _open_regular(path: Path) -> Iterator[BinaryIO]:
    """A file checked by :func:`_not_regular`, opened without following a link and refused
    unless still a regular file (it may have been swapped since the check)."""
    descriptor = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    with os.fdopen(descriptor, "rb") as handle:
        if not stat.S_ISREG(os.fstat(handle.fileno()).st_mode):
            raise ResultsError(f"{path}: not a regular file")
        yield handle


def _read_regular(path: Path) -> bytes:
    with _open_regular(path) as handle:
        return handle.read()


def _sha256_regular(path: Path) -> str:
    digest = hashlib.sha256()
    with _open_regular(path) as handle:
        for chunk in iter(lambda: handle.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def _entries(bundle: Path) -> Iterator[tuple[str, str | None]]:
    """Every entry below ``bundle`` that is not a folder, with why it is not a regular file
    (None when it is); links are reported, never followed."""
    for folder, folders, names in os.walk(bundle, followlinks=False):
        here = Path(folder)
        for name in sorted([*folders, *names]):
            path = here / name
            mode = path.lstat().st_mode
            if stat.S_ISDIR(mode):
                continue
            relative = path.relative_to(bundle).as_posix()
            if stat.S_ISLNK(mode):
                yield relative, "is a symbolic link (a bundle holds regular files only)"
            elif not stat.S_ISREG(mode):
                yield relative, "is not a regular file"
            else:
                yield relative, None


def _short(value: object) -> str:
    text = " ".join(str(value).split())
    return text if len(text) <= 200 else text[:197] + "..."


def _check_scenario(
    bundle: Path, entry: Mapping[str, Any], files: Mapping[str, str], verified: set[str]
) -> list[str]:
    problems = []
    scenario_id = entry.get("id", "?")
    for item, described in dict(entry.get("items", {})).items():
        if not described.get("included"):
            continue
        relative = described.get("path", "")
        if files.get(relative) != described.get("sha256"):
            problems.append(f"{scenario_id}: {item} digest differs from the file list")
        recorded = described.get("recorded_sha256")
        if recorded and recorded != described.get("sha256"):
            problems.append(
                f"{scenario_id}: {item} sha256 {described.get('sha256')} is not the one recorded "
                f"at run time ({recorded})"
            )
    verdict_item = dict(entry.get("items", {})).get("verdict", {})
    relative = verdict_item.get("path", "")
    if verdict_item.get("included") and relative in verified:
        try:
            loaded = json.loads(_read_regular(bundle / relative))
        except (ValueError, RecursionError):
            loaded = None
        stated = loaded.get("verdict") if isinstance(loaded, dict) else None
        if stated != entry.get("verdict"):
            problems.append(f"{scenario_id}: verdict.json says {stated!r}, the manifest "
                            f"{entry.get('verdict')!r}")  # fmt: skip
    return problems


def newest_run(db: ReadOnlyDatabase) -> str:
    """The key of the newest campaign run (what export uses without ``--run``)."""
    rows = db.query("SELECT run_key FROM campaigns ORDER BY started_at DESC, run_key DESC LIMIT 1")
    if not rows:
        raise ResultsError(f"no campaign runs in {db.where}")
    return str(rows[0][0])
