"""Catalog resolution: CatalogLocations directories, entries by name, ParameterAssignments.

Catalog files are found through the scenario's ``CatalogLocations`` (directories relative to the
.xosc), parsed once per load, and indexed by catalog name and entry name. Real files often use a
``catalogName`` that differs from the catalog's declared ``name`` (esmini resolves by entry name),
so an exact (catalog, entry) match is preferred and a unique-by-entry-name match is accepted.

Catalog directories must lie inside the scenario's source root (:mod:`.confinement`); one that
points outside is never read, and a catalog file that is a symlink out of its directory is
skipped. Catalog files from before 1.0 (``revMajor="0"``, CARLA's 0.9 catalogs) hold the same
entries and are read with a deviation.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path

from simtest_operator import xmlsafe
from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import parameters, reading
from simtest_operator.openscenario.confinement import Confinement
from simtest_operator.xmlsafe import Element

LOCATION_KINDS: Mapping[str, str] = {
    "VehicleCatalog": "Vehicle",
    "ControllerCatalog": "Controller",
    "PedestrianCatalog": "Pedestrian",
    "MiscObjectCatalog": "MiscObject",
    "EnvironmentCatalog": "Environment",
    "ManeuverCatalog": "Maneuver",
    "TrajectoryCatalog": "Trajectory",
    "RouteCatalog": "Route",
}
"""CatalogLocations child element -> the entry element its catalogs hold."""

MAX_NESTING = 16
"""Deepest chain of catalog entries referring to other catalog entries."""


@dataclasses.dataclass(frozen=True, slots=True)
class Entry:
    """One catalog entry: its element, the catalog it is in, and the file."""

    element: Element
    catalog_name: str
    entry_name: str
    file: str


@dataclasses.dataclass(frozen=True, slots=True)
class _Directory:
    path: Path
    kind: str
    line: int | None
    outside: bool = False
    """Outside the source root: never read."""


class Catalogs:
    """The catalogs of one scenario load (parses catalog files lazily, once)."""

    def __init__(
        self,
        directories: tuple[_Directory, ...],
        *,
        scenario_file: str,
        max_bytes: int = xmlsafe.MAX_BYTES,
        refusal: str = "",
    ) -> None:
        self._directories = directories
        self._refusal = refusal
        self._scenario_file = scenario_file
        self._max_bytes = max_bytes
        self._entries: dict[Path, tuple[Entry, ...]] = {}

    @classmethod
    def from_locations(
        cls,
        root: Element,
        ctx: reading.Context,
        base: Path,
        *,
        confinement: Confinement,
        max_bytes: int = xmlsafe.MAX_BYTES,
    ) -> Catalogs:
        """Read ``CatalogLocations`` of the scenario ``root``; directories relative to ``base``,
        confined to ``confinement``; catalog files up to ``max_bytes``."""
        found: list[_Directory] = []
        block = reading.child(root, "CatalogLocations")
        for location in reading.children(block) if block is not None else ():
            kind = LOCATION_KINDS.get(str(location.tag))
            if kind is None:
                raise ctx.error(location, "unknown catalog location kind")
            directory = ctx.require(location, "Directory")
            path = (base / ctx.string(directory, "path")).resolve()
            outside = not confinement.allows(path)
            found.append(_Directory(path, kind, directory.sourceline, outside))
        return cls(
            tuple(found),
            scenario_file=ctx.file,
            max_bytes=max_bytes,
            refusal=confinement.describe(),
        )

    @classmethod
    def empty(cls, *, scenario_file: str) -> Catalogs:
        """No catalogs (used while reading the CatalogLocations themselves)."""
        return cls((), scenario_file=scenario_file)

    def find(
        self, ref: Element, ctx: reading.Context, expected: tuple[str, ...]
    ) -> tuple[Entry, reading.Context]:
        """Resolve the CatalogReference ``ref`` to an entry whose tag is one of ``expected``.

        Returns the entry and a context for reading it: the entry's file, the global scope and the
        reference's ParameterAssignments pending for the entry's declarations.
        """
        catalog_name = ctx.string(ref, "catalogName")
        entry_name = ctx.string(ref, "entryName")
        if ctx.depth >= MAX_NESTING:
            raise ctx.error(ref, f"catalog references nested deeper than {MAX_NESTING}")
        entry = self._lookup(ref, ctx, catalog_name, entry_name, expected)
        assignments: dict[str, str] = {}
        block = reading.child(ref, "ParameterAssignments")
        for assignment in (
            reading.all_children(block, "ParameterAssignment") if block is not None else ()
        ):
            # parameterRef names a parameter; esmini files sometimes write it as "$name".
            name = (ctx.raw(assignment, "parameterRef") or "").strip().removeprefix("$")
            if not name:
                raise ctx.error(assignment, "missing required attribute 'parameterRef'")
            raw = ctx.raw(assignment, "value")
            if raw is None:
                raise ctx.error(assignment, "missing required attribute 'value'")
            try:
                assignments[name] = parameters.to_text(parameters.resolve(raw, ctx.scope))
            except ScenarioError as exc:
                raise ctx.error(assignment, str(exc.args[0])) from exc
        inner = ctx.for_entry(entry.file, assignments)
        return entry, inner

    def _lookup(
        self,
        ref: Element,
        ctx: reading.Context,
        catalog_name: str,
        entry_name: str,
        expected: tuple[str, ...],
    ) -> Entry:
        kinds = "/".join(expected)
        if not self._directories:
            raise ctx.error(
                ref,
                f"catalog {catalog_name!r} entry {entry_name!r}: the scenario declares no "
                f"CatalogLocations for {kinds}",
            )
        # Directories of the expected kinds first, then the rest (mis-filed entries).
        ordered = sorted(self._directories, key=lambda d: d.kind not in expected)
        by_name: list[Entry] = []
        missing: list[str] = []
        refused: list[str] = []
        for directory in ordered:
            if directory.outside:
                refused.append(str(directory.path))
                continue
            if not directory.path.is_dir():
                missing.append(str(directory.path))
                continue
            for entry in self._load(directory, ctx):
                if entry.entry_name != entry_name or str(entry.element.tag) not in expected:
                    continue
                if entry.catalog_name == catalog_name:
                    return entry
                by_name.append(entry)
        if by_name:
            return by_name[0]
        where = "; missing directories: " + ", ".join(missing) if missing else ""
        if refused:
            where += f"; refused ({self._refusal}): " + ", ".join(refused)
        raise ctx.error(
            ref,
            f"catalog {catalog_name!r} has no {kinds} entry {entry_name!r} in "
            + ", ".join(str(d.path) for d in ordered)
            + where,
        )

    def _load(self, directory: _Directory, ctx: reading.Context) -> tuple[Entry, ...]:
        cached = self._entries.get(directory.path)
        if cached is not None:
            return cached
        entries: list[Entry] = []
        for path in sorted(directory.path.glob("*.xosc")):
            if not path.resolve().is_relative_to(directory.path):
                continue  # a symlink out of the catalog directory
            root = xmlsafe.parse_file(path, max_bytes=self._max_bytes)
            catalog = reading.child(root, "Catalog")
            if catalog is None:
                continue
            _check_revision(root, ctx, str(path))
            name = catalog.get("name") or ""
            for element in reading.children(catalog):
                entry_name = element.get("name")
                if entry_name is None:
                    raise ScenarioError(
                        "catalog entry without a name",
                        file=str(path),
                        element=str(element.tag),
                        line=element.sourceline,
                    )
                entries.append(Entry(element, name, entry_name, str(path)))
        result = tuple(entries)
        self._entries[directory.path] = result
        return result


def _check_revision(root: Element, ctx: reading.Context, file: str) -> None:
    header = reading.child(root, "FileHeader")
    if header is None or header.get("revMajor") != "0":
        return
    # OpenSCENARIO 0.9 (CARLA's catalogs) wrote catalog entries as 1.0 does.
    at_file = dataclasses.replace(ctx, file=file)
    minor = header.get("revMinor") or "?"
    at_file.deviation(header, "catalog-revision-0", f"0.{minor} catalog header read as 1.0")
