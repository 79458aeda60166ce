"""Where a scenario may read other files from: its source tree and the map libraries.

A scenario names other files (``LogicFile``, ``CatalogLocations``); a file from a campaign source
is untrusted, so following ``/etc/passwd`` or ``../../proc/self/environ`` would read and parse
whatever the worker can see. Every reference is resolved (``..`` and symlinks included) and must
land inside the scenario's *source root*; road networks may also come from a map library
(:mod:`simtest_operator.maps`).

The source root is the caller's to give (``LoadOptions.source_root``): the folder
``simtest scenario check`` was pointed at (or its ``--root``); ``--root`` of
``simtest scenario run`` (default: the enclosing git work tree, else the scenario's folder).
A campaign's scenario gets the folder its source was fetched into (a git tree at its commit, an
unpacked archive, a database's or ConfigMap's files: ``scenarios.uris.source_root``). Relative
references within a tree (``../catalogs``) keep working. A caller that gives none -- a campaign's
local ``path`` source, the user's own files -- gets the enclosing git work tree, or outside any
only the system folders (:data:`SYSTEM`) refused.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

SYSTEM = tuple(Path(p) for p in ("/proc", "/sys", "/dev", "/etc", "/boot", "/run", "/var/run"))
"""Never a scenario's data, whatever the root: kernel interfaces, configuration, secrets. (Not
home folders: root's holds the source cache, ``~/.cache/simtest``, when the tools run as root.)"""


@dataclasses.dataclass(frozen=True, slots=True)
class Confinement:
    """The folder references may resolve into (absolute, symlinks resolved), if one is known."""

    source_root: Path | None

    @classmethod
    def for_scenario(cls, scenario: Path, source_root: Path | None) -> Confinement:
        """The confinement of ``scenario`` under ``source_root`` (or its git work tree)."""
        root = source_root or git_root(scenario)
        return cls(root.resolve() if root is not None else None)

    def allows(self, path: Path) -> bool:
        """Whether ``path`` (after resolving ``..`` and symlinks) may be read."""
        real = path.resolve()
        if any(real.is_relative_to(system) for system in SYSTEM):
            return False
        return self.source_root is None or real.is_relative_to(self.source_root)

    def describe(self) -> str:
        """Where references may point, for error messages."""
        if self.source_root is None:
            return "in a system folder (" + ", ".join(str(s) for s in SYSTEM) + ")"
        return f"outside the scenario's source root {self.source_root}"


def git_root(scenario: Path) -> Path | None:
    """The nearest enclosing git work tree of ``scenario``, or None."""
    folder = scenario.resolve().parent
    for candidate in (folder, *folder.parents):
        if (candidate / ".git").exists():
            return candidate
    return None


def default_root(scenario: Path) -> Path:
    """The scenario's own tree: its enclosing git work tree, else its folder."""
    return git_root(scenario) or scenario.resolve().parent
