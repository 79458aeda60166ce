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

import dataclasses
import hashlib
import json
import re
import shutil
import urllib.parse
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

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
    """Recompute every digest of ``bundle``: (manifest sha256, problems); no problems = valid."""
    manifest_path = bundle / MANIFEST
    if not manifest_path.is_file():
        raise ResultsError(f"{bundle} is not an evidence bundle: no {MANIFEST}")
    content = manifest_path.read_bytes()
    digest = hashlib.sha256(content).hexdigest()
    problems: list[str] = []
    stated = bundle / MANIFEST_DIGEST
    if stated.is_file() and stated.read_text(encoding="utf-8").split()[:1] != [digest]:
        problems.append(f"{MANIFEST}: digest {digest} differs from {MANIFEST_DIGEST}")
    try:
        manifest = json.loads(content)
        files: dict[str, str] = dict(manifest["files"])
        scenarios = list(manifest["scenarios"])
    except (ValueError, KeyError, TypeError) as exc:
        raise ResultsError(f"{manifest_path}: not a {FORMAT} manifest ({exc})") from None
    if manifest.get("format") != FORMAT:
        raise ResultsError(f"{manifest_path}: format {manifest.get('format')!r}, not {FORMAT}")
    for relative, expected in sorted(files.items()):
        path = bundle / relative
        if ".." in Path(relative).parts or Path(relative).is_absolute():
            problems.append(f"{relative}: path leaves the bundle")
        elif not path.is_file():
            problems.append(f"{relative}: missing")
        elif (actual := sha256_file(path)) != expected:
            problems.append(f"{relative}: sha256 {actual}, manifest says {expected}")
    present = {p.relative_to(bundle).as_posix() for p in bundle.rglob("*") if p.is_file()} - {
        MANIFEST,
        MANIFEST_DIGEST,
    }
    problems += [f"{extra}: not listed in the manifest" for extra in sorted(present - set(files))]
    for entry in scenarios:
        problems += _check_scenario(bundle, entry, files)
    return digest, tuple(problems)


def _check_scenario(bundle: Path, entry: Mapping[str, Any], files: Mapping[str, str]) -> list[str]:
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
    verdict_path = bundle / verdict_item.get("path", "")
    if verdict_item.get("included") and verdict_path.is_file():
        try:
            stated = json.loads(verdict_path.read_text(encoding="utf-8")).get("verdict")
        except ValueError:
            stated = None
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
