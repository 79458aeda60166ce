"""Road network libraries: OpenDRIVE maps a scenario names by name instead of by path.

Files written for CARLA name their road network by town (``<LogicFile filepath="Town01"/>``);
CARLA resolves that to a built-in map. The product ships the CARLA towns that are redistributable
(``carla/``: OpenDRIVE, MIT, with their LICENSE and provenance README) and lets users add their
own libraries (``SIMTEST_MAP_PATH``, ``--maps``): folders of ``<name>.xodr`` files. A name is
looked up in the user libraries first (in the order given), then in the shipped one, so a user
can replace a town with a newer export.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path

SHIPPED = Path(__file__).resolve().parent / "carla"
"""The CARLA towns shipped with the product (package data)."""

SUFFIX = ".xodr"


@dataclasses.dataclass(frozen=True, slots=True)
class MapLibraries:
    """The folders searched for a road network named by name, highest priority first."""

    folders: tuple[Path, ...]

    @classmethod
    def with_user(cls, user: Sequence[Path] = ()) -> MapLibraries:
        """The user's folders (in order), then the shipped CARLA towns."""
        resolved = tuple(dict.fromkeys(p.expanduser().resolve() for p in (*user, SHIPPED)))
        return cls(resolved)

    def find(self, name: str) -> Path | None:
        """The map called ``name`` (``Town01`` or ``Town01.xodr``), or None.

        Only plain names are looked up: a name with a path separator or ``..`` never leaves a
        library folder, and a symlink in a library that points elsewhere is not followed.
        """
        stem = name.removesuffix(SUFFIX)
        if not is_map_name(stem):
            return None
        for folder in self.folders:
            candidate = folder / f"{stem}{SUFFIX}"
            if candidate.is_file() and candidate.resolve().is_relative_to(folder):
                return candidate.resolve()
        return None

    def names(self) -> tuple[str, ...]:
        """Every map name available, sorted (for error messages and docs)."""
        found = {p.stem for f in self.folders if f.is_dir() for p in f.glob(f"*{SUFFIX}")}
        return tuple(sorted(found))


def is_map_name(text: str) -> bool:
    """Whether ``text`` is a plain map name (no path separators, not ``.``/``..``, not empty)."""
    return bool(text) and "/" not in text and "\\" not in text and text not in (".", "..")
