"""OpenDRIVE -> SUMO network conversion with netconvert, cached by content hash.

Converting a map takes 0.2-0.5 s and the same few maps back thousands of runs, so each converted
``.net.xml`` is kept under ``settings.cache.nets`` named by the SHA-256 of the map content, the
netconvert flags and the SUMO version. Files appear atomically (temp file + rename), so processes
converting the same map at the same time are safe: the last rename wins with identical content.

A converted network can also ship with its map: ``simtest scenario nets DIR`` writes it, under the
same key, into ``.simtest-nets/`` beside the map, and :func:`ensure_net` looks there first. That is
how simulator pods skip netconvert: their own cache is on the pod's ``emptyDir`` and dies with it,
while the shipped folder travels read-only with the scenario volume. The key names the map's
content, the flags and the SUMO version, so a shipped network is used only for the very map it
was made from by the same netconvert; anything else is a miss and converts as before
(docs/simulator.md, "Converted networks shipped with the scenarios", says why not a node cache).

The flags keep SUMO's x/y equal to OpenDRIVE's (no offset normalisation) and annotate every SUMO
lane with ``origId="<road>_<lane>"``. Constant-curvature spirals and straight arcs, which netconvert
cannot evaluate, are first rewritten as the equivalent arc or line
(:func:`~simtest_operator.opendrive.flat_curves_rewritten`). Known-broken real maps are retried with
``--ignore-errors`` and then on a copy without ``<signal>`` elements (see notes/sumo-mapping.md).
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.metadata
import subprocess
import tempfile
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

import sumo

from simtest_operator import opendrive, xmlsafe
from simtest_operator.errors import ScenarioError, SimulationError

NETCONVERT_FLAGS: tuple[str, ...] = (
    "--offset.disable-normalization",
    "true",
    "--output.original-names",
    "true",
    "--opendrive.internal-shapes",
    "true",
    "--no-warnings",
    "true",
)
"""Flags of every conversion (part of the cache key)."""

_STRATEGY = "v2: flat curves rewritten; plain, ignore-errors, no-signals, no-signals+ignore-errors"
"""Names the fallback sequence; changing it invalidates cached nets."""
_IGNORE_ERRORS = ("--ignore-errors", "true")
_STDERR_TAIL = 20

SHIPPED_DIR = ".simtest-nets"
"""Folder beside a map holding its shipped conversions (``<key>.net.xml``)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ConvertedNet:
    """A SUMO network ready to load."""

    path: Path
    from_cache: bool
    """Found converted (shipped beside the map or in the cache): netconvert did not run."""
    seconds: float
    """Wall time spent here (hash + lookup on a hit, conversion on a miss)."""


def netconvert_binary() -> Path:
    """netconvert shipped in the ``eclipse-sumo`` wheel."""
    binary = Path(sumo.SUMO_HOME) / "bin" / "netconvert"
    if not binary.is_file():
        raise SimulationError(f"netconvert not found at {binary}; reinstall the eclipse-sumo wheel")
    return binary


def sumo_version() -> str:
    try:
        return importlib.metadata.version("eclipse-sumo")
    except importlib.metadata.PackageNotFoundError as exc:
        raise SimulationError("the eclipse-sumo package is not installed") from exc


def cache_key(content: bytes) -> str:
    digest = hashlib.sha256(content)
    for part in (*NETCONVERT_FLAGS, _STRATEGY, sumo_version()):
        digest.update(b"\0" + part.encode())
    return digest.hexdigest()


def shipped_dir(xodr: Path) -> Path:
    """Where the conversions shipped with the map ``xodr`` live."""
    return xodr.parent / SHIPPED_DIR


def ensure_net(xodr: Path, *, cache_dir: Path, timeout: float = 300.0) -> ConvertedNet:
    """The SUMO network for the OpenDRIVE file ``xodr``: the one shipped beside it, else the
    cached one, else converted into ``cache_dir``.

    Raises ScenarioError if the map cannot be read and SimulationError if netconvert fails on
    every fallback (the message ends with netconvert's last stderr lines).
    """
    started = time.perf_counter()
    try:
        content = xodr.read_bytes()
    except OSError as exc:
        raise ScenarioError(f"cannot read OpenDRIVE file: {exc}", file=str(xodr)) from exc
    name = f"{cache_key(content)}.net.xml"
    target = cache_dir / name
    for found in (shipped_dir(xodr) / name, target):
        if found.is_file() and found.stat().st_size > 0:
            return ConvertedNet(path=found, from_cache=True, seconds=time.perf_counter() - started)
    cache_dir.mkdir(parents=True, exist_ok=True)
    _convert(xodr, content, target, timeout=timeout)
    return ConvertedNet(path=target, from_cache=False, seconds=time.perf_counter() - started)


def ship_net(xodr: Path, *, timeout: float = 300.0) -> ConvertedNet:
    """Convert ``xodr`` into its shipped folder (if not there yet), for pods to find read-only."""
    return ensure_net(xodr, cache_dir=shipped_dir(xodr), timeout=timeout)


def _convert(xodr: Path, content: bytes, target: Path, *, timeout: float) -> None:
    failures: list[str] = []
    with tempfile.TemporaryDirectory(prefix="netconvert-", dir=target.parent) as work:
        work_dir = Path(work)
        stripped: Path | None = None
        converted = xodr
        rewritten = opendrive.flat_curves_rewritten(content, source=str(xodr))
        if rewritten is not None:
            content, converted = rewritten, work_dir / "curves.xodr"
            converted.write_bytes(rewritten)
        attempts: list[tuple[str, Path | None, Sequence[str]]] = [
            ("plain", converted, ()),
            ("--ignore-errors", converted, _IGNORE_ERRORS),
            ("without signals", None, ()),
            ("without signals, --ignore-errors", None, _IGNORE_ERRORS),
        ]
        for label, source, extra in attempts:
            if source is None:
                if stripped is None:
                    stripped = work_dir / "stripped.xodr"
                    stripped.write_bytes(opendrive.without_signals(content, source=str(xodr)))
                source = stripped
            output = work_dir / "out.net.xml"
            result = _run(source, output, extra, timeout=timeout)
            if result.returncode == 0 and output.is_file() and output.stat().st_size > 0:
                # Same directory as the target, so the rename is atomic.
                output.replace(target)
                return
            tail = "\n".join(result.stderr.strip().splitlines()[-_STDERR_TAIL:])
            failures.append(f"[{label}] rc={result.returncode}: {tail}")
    raise SimulationError(
        f"netconvert failed on {xodr} with every fallback:\n" + "\n".join(failures)
    )


def _run(
    source: Path, output: Path, extra: Sequence[str], *, timeout: float
) -> subprocess.CompletedProcess[str]:
    command = [
        str(netconvert_binary()),
        "--opendrive-files",
        str(source),
        "--output-file",
        str(output),
        *NETCONVERT_FLAGS,
        *extra,
    ]
    try:
        return subprocess.run(
            command,
            capture_output=True,
            text=True,
            timeout=timeout,
            env={"SUMO_HOME": str(sumo.SUMO_HOME)},
            check=False,
        )
    except subprocess.TimeoutExpired as exc:
        raise SimulationError(f"netconvert timed out after {timeout:.0f} s on {source}") from exc
    except OSError as exc:
        raise SimulationError(f"cannot run netconvert: {exc}") from exc


NET_MAX_BYTES = 1024 * 1024 * 1024
"""Largest SUMO network read for its lane origins (a 32 MB map converts to 66 MB)."""


def lane_origins(net_path: Path) -> Mapping[tuple[str, int], tuple[str, ...]]:
    """OpenDRIVE (road id, lane id) -> SUMO lane ids, from the ``origId`` lane parameters.

    Normal lanes of split lane sections map several SUMO lanes to one OpenDRIVE lane (ordered as
    in the net file); junction connecting roads map to internal lanes (``:<junction>_<n>_<i>``).
    The file is streamed one edge at a time: sumolib's object model of a 21,000-road map took
    840 MB and 25 s, most of a simulator pod's memory (issue 29).
    """
    try:
        data = net_path.read_bytes()
        mapping: dict[tuple[str, int], list[str]] = {}
        for element in xmlsafe.stream_children(
            data, source=str(net_path), max_bytes=NET_MAX_BYTES, what="SUMO network"
        ):
            if element.tag != "edge":
                continue
            for lane in element:
                if lane.tag != "lane":
                    continue
                for param in lane:
                    if param.tag == "param" and param.get("key") == "origId":
                        _add_origins(mapping, str(lane.get("id")), param.get("value") or "")
    except (OSError, ScenarioError) as exc:
        raise SimulationError(f"cannot read SUMO network {net_path}: {exc}") from exc
    return {key: tuple(value) for key, value in mapping.items()}


def _add_origins(mapping: dict[tuple[str, int], list[str]], lane_id: str, origins: str) -> None:
    for origin in origins.split():
        road_id, _, lane = origin.rpartition("_")
        try:
            key = (road_id, int(lane))
        except ValueError:
            continue
        mapping.setdefault(key, []).append(lane_id)
