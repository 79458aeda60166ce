"""Value documents: deep merge with Helm semantics, canonical text and content hashes.

Rendering must be byte-for-byte reproducible: the same inputs give the same files and the same
hash, which goes into the SimEnvironment's status so a run can be traced to exactly what it ran.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from typing import Any

import yaml

# libyaml's C loader and dumper when PyYAML was built with it (the wheels are): same documents,
# 5-6x faster, and rendering runs on the operator's event loop once per environment.
_LOADER: type[yaml.SafeLoader] = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
_DUMPER: type[yaml.SafeDumper] = getattr(yaml, "CSafeDumper", yaml.SafeDumper)


def deep_merge(base: Mapping[str, Any], override: Mapping[str, Any]) -> dict[str, Any]:
    """Merge ``override`` into ``base`` like ``helm --values``: mappings merge recursively, other
    values (lists included) replace, and ``None`` removes the key."""
    merged: dict[str, Any] = {key: _copy(value) for key, value in base.items()}
    for key, value in override.items():
        if value is None:
            merged.pop(key, None)
        elif isinstance(value, Mapping) and isinstance(merged.get(key), Mapping):
            merged[key] = deep_merge(merged[key], value)
        else:
            merged[key] = _copy(value)
    return merged


def _copy(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _copy(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_copy(v) for v in value]
    return value


def canonical_json(value: Any) -> str:
    """Sorted keys, no insignificant whitespace, UTF-8 kept: one text per value."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=False)


def content_hash(value: Any) -> str:
    """sha256 (hex) of :func:`canonical_json`."""
    return hashlib.sha256(canonical_json(value).encode("utf-8")).hexdigest()


def to_yaml(value: Any) -> str:
    """Block-style YAML with sorted keys (stable across runs and Python versions)."""
    text = yaml.dump(
        _copy(value),
        Dumper=_DUMPER,
        sort_keys=True,
        default_flow_style=False,
        allow_unicode=True,
        width=100,
    )
    return str(text)


def from_yaml(text: str) -> Any:
    """Parse one YAML document safely (no tags beyond the standard ones)."""
    return yaml.load(text, Loader=_LOADER)
