"""The protobuf schema stored in each recording: OSI 3.7.0's descriptor set, trimmed.

MCAP protobuf channels carry a FileDescriptorSet as schema. betterosi ships OSI's complete set
(730 kB, stored twice per file: about 1.5 MB of fixed overhead per recording). Only the files that
GroundTruth and MapAsamOpenDrive depend on are kept, without source comments (about 56 kB);
omega-prime and protobuf decoders read the result. The set is read from betterosi's package data
without importing betterosi (0.4 s), and split with a minimal wire-format reader.
"""

from __future__ import annotations

import functools
import importlib.util
from pathlib import Path

from simtest_operator.errors import ResultsError
from simtest_operator.recording import osiwire

ROOT_FILES = ("osi_groundtruth.proto", "osi_mapasamopendrive.proto")
_FILE_NAME, _FILE_DEPENDENCY, _FILE_SOURCE_INFO = 1, 3, 9


def _osi_descriptor_path(version: str) -> Path:
    spec = importlib.util.find_spec("betterosi")
    if spec is None or not spec.submodule_search_locations:
        raise ResultsError("the betterosi package is not installed")
    base = Path(next(iter(spec.submodule_search_locations)))
    return base / "generated" / version / "osi3_descriptor_set.pb"


def trim(descriptor_set: bytes, roots: tuple[str, ...] = ROOT_FILES) -> bytes:
    """Keep ``roots`` and their transitive dependencies, dropping source code info."""
    files: dict[str, tuple[bytes, list[str]]] = {}
    order: list[str] = []
    for field, _, raw in osiwire.fields(descriptor_set):
        if field != 1:
            continue
        body = osiwire.payload(raw)
        name = ""
        dependencies: list[str] = []
        kept = bytearray()
        for inner, _, inner_raw in osiwire.fields(body):
            if inner == _FILE_NAME:
                name = osiwire.payload(inner_raw).decode()
            elif inner == _FILE_DEPENDENCY:
                dependencies.append(osiwire.payload(inner_raw).decode())
            if inner != _FILE_SOURCE_INFO:
                kept += inner_raw
        files[name] = (bytes(kept), dependencies)
        order.append(name)
    needed: set[str] = set()
    pending = [root for root in roots if root in files]
    while pending:
        name = pending.pop()
        if name in needed:
            continue
        needed.add(name)
        pending.extend(dep for dep in files[name][1] if dep in files)
    return b"".join(osiwire.length_delimited(1, files[name][0]) for name in order if name in needed)


@functools.cache
def osi_descriptor_set(version: str = "3.7.0") -> bytes:
    """The trimmed OSI FileDescriptorSet (computed once per process)."""
    path = _osi_descriptor_path(version)
    try:
        return trim(path.read_bytes())
    except OSError as exc:
        raise ResultsError(f"cannot read the OSI descriptor set {path}: {exc}") from exc
