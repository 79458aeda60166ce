"""ConfigMaps read from the folders a simulator pod mounts them at.

In a pod the runner has no API access (no service-account token), so the operator mounts every
ConfigMap the pod's scenarios name as a read-only configMap volume at ``<root>/<name>/``; the
kubelet writes one file per key (``data`` and ``binaryData`` alike) as a symlink into a hidden
``..data`` folder. This reader turns such a folder back into the key -> bytes mapping resolution
expects, bounded like any source: valid ConfigMap keys only, no path leaving the folder, at most
``max_files`` keys of at most ``max_scenario_bytes`` each.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping
from pathlib import Path

from simtest_operator.errors import SourceError
from simtest_operator.scenarios.specs import SourceLimits

_KEY = re.compile(r"^[-._a-zA-Z0-9]{1,253}$")
"""A ConfigMap key (the API server's rule); ``.``/``..`` and the kubelet's ``..`` entries aside."""
_NAME = re.compile(r"^[a-z0-9]([-a-z0-9.]{0,251}[a-z0-9])?$")


def is_key(key: str) -> bool:
    """Whether ``key`` is a ConfigMap key (and not one of the kubelet's ``..`` entries)."""
    return bool(_KEY.match(key)) and not key.startswith("..") and key != "."


@dataclasses.dataclass(frozen=True, slots=True)
class MountedConfigMaps:
    """A :data:`~simtest_operator.scenarios.resolving.ConfigMapReader` over mounted folders."""

    root: Path
    """The folder holding one mounted folder per ConfigMap name."""
    limits: SourceLimits = dataclasses.field(default_factory=SourceLimits)

    def __call__(self, name: str) -> Mapping[str, bytes]:
        if not _NAME.match(name):
            raise SourceError(f"ConfigMap name {name!r} is not a valid object name")
        folder = self.root / name
        if not folder.is_dir():
            raise SourceError(
                f"ConfigMap {name!r} is not mounted in this pod (no folder {folder}); it was "
                "deleted after the campaign resolved, or the pod template drops the operator's "
                "scenario volumes"
            )
        real = folder.resolve()
        data: dict[str, bytes] = {}
        for entry in sorted(folder.iterdir()):
            if not is_key(entry.name):
                continue
            target = entry.resolve()
            if not target.is_relative_to(real) or not target.is_file():
                continue
            if len(data) >= self.limits.max_files:
                raise SourceError(f"ConfigMap {name!r}: more than {self.limits.max_files} keys")
            data[entry.name] = _read(target, self.limits.max_scenario_bytes, f"{name}/{entry.name}")
        return data


def _read(path: Path, limit: int, where: str) -> bytes:
    try:
        with path.open("rb") as handle:
            content = handle.read(limit + 1)
    except OSError as exc:
        raise SourceError(f"ConfigMap key {where}: cannot read ({exc.strerror})") from exc
    if len(content) > limit:
        raise SourceError(f"ConfigMap key {where} is larger than {limit} bytes")
    return content
