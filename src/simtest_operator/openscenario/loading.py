"""Loading an OpenSCENARIO 1.0-1.3 scenario file into the typed model.

This is the entry point the engine and the CLI call: safe XML parse, global parameters (with
caller overrides), catalogs, road network, entities and storyboard, and the list of unsupported
elements. Everything below works on lxml elements; nothing above sees XML.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path

from simtest_operator import xmlsafe
from simtest_operator.errors import ScenarioError
from simtest_operator.maps import MapLibraries
from simtest_operator.openscenario import headers, parameters, reading, rulesets
from simtest_operator.openscenario.catalogs import Catalogs
from simtest_operator.openscenario.confinement import Confinement
from simtest_operator.openscenario.deviations import Deviations
from simtest_operator.openscenario.headers import FileKind
from simtest_operator.openscenario.model import common as m
from simtest_operator.openscenario.model import entities as e
from simtest_operator.openscenario.model import scenarios as s
from simtest_operator.openscenario.readers import (
    entities,
    monitors,
    selections,
    storyboards,
    traffic_signals,
)
from simtest_operator.xmlsafe import Element


def file_kind_of(root: Element, *, file: str) -> FileKind:
    """Classify a parsed OpenSCENARIO root element."""
    if root.tag != "OpenSCENARIO":
        raise ScenarioError(
            f"not an OpenSCENARIO file (root element <{root.tag}>)", file=file, line=root.sourceline
        )
    if reading.child(root, "Catalog") is not None:
        return FileKind.CATALOG
    if reading.child(root, "ParameterValueDistribution") is not None:
        return FileKind.DISTRIBUTION
    return FileKind.SCENARIO


def file_kind(path: Path) -> FileKind:
    """Classify the .xosc file at ``path`` (scenario, catalog or parameter distribution) from
    its first elements, without parsing the rest."""
    kind = headers.read_header(path).kind
    if kind is FileKind.UNKNOWN:
        raise ScenarioError("not a scenario, catalog or parameter distribution", file=str(path))
    return kind


MAX_SCENARIO_BYTES = 8 * 1024 * 1024
"""Default size limit of scenario and catalog files: real ones are below 1 MB; 8 MB parse in
about 180 MB, which fits a simulator pod's memory request beside SUMO (docs/openscenario-support.md
has the measurements)."""

MAX_ENTITIES = 500
"""ScenarioObjects per scenario. Every entity is moved, checked for collisions and recorded each
step: 1,000 took 56 s of wall time for 10 s simulated, and 5,000 never got past 0 s before the
campaign's timeout killed the simulator, a ``Timeout`` blamed on the system under test (issue 29).
Real files have up to a few dozen; traffic belongs in swarms and SUMO's own vehicles."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LoadOptions:
    """How strictly and from where a scenario is loaded (the caller's policy, not the file's)."""

    strict: bool = False
    """Refuse accepted deviations from the schema (see :mod:`.deviations`) instead of listing
    them: for authors who want files every player reads."""
    source_root: Path | None = None
    """Folder every referenced file (road network, catalogs) must be in; None: the enclosing git
    work tree, else only system folders refused (see :mod:`.confinement`)."""
    maps: tuple[Path, ...] = ()
    """User map libraries (folders of ``<name>.xodr``) searched before the shipped CARLA towns
    for a ``LogicFile`` that names a map."""
    max_bytes: int = MAX_SCENARIO_BYTES
    """Size limit of the scenario and of each catalog file (loading takes ~20x in memory)."""


DEFAULT_OPTIONS = LoadOptions()


def load_scenario(
    path: Path,
    *,
    overrides: Mapping[str, str] | None = None,
    options: LoadOptions = DEFAULT_OPTIONS,
) -> s.Scenario:
    """Load the scenario at ``path``; ``overrides`` replace global parameter values (as text).

    Raises ScenarioError (file, element, line) for unusable input: unsafe or malformed XML, a
    catalog or distribution file, undeclared or mistyped parameters, missing catalogs or entries,
    a missing road network. Unsupported-but-parseable elements do not raise; they are in
    ``scenario.unsupported()``. A file under ScenarioRunner's rules (:mod:`.rulesets`) has its
    lateral offsets from the road read positive to the right, as ScenarioRunner places them.
    """
    scenario = _load(path, overrides, options, rulesets.OPENSCENARIO)
    rules = rulesets.rules_of(scenario)
    if rules.scenario_runner and not scenario.header.description.startswith(rulesets.CARLA_PREFIX):
        # Its conventions show up only once read: read again with ScenarioRunner's offsets.
        scenario = _load(path, overrides, options, rules)
    return scenario


def _load(
    path: Path,
    overrides: Mapping[str, str] | None,
    options: LoadOptions,
    rules: rulesets.Rules,
) -> s.Scenario:
    path = path.resolve()
    file = str(path)
    confinement = Confinement.for_scenario(path, options.source_root)
    if not confinement.allows(path):
        raise ScenarioError(f"scenario is {confinement.describe()}", file=file)
    root = xmlsafe.parse_file(path, max_bytes=options.max_bytes)
    kind = file_kind_of(root, file=file)
    if kind is not FileKind.SCENARIO:
        hint = " (use expand_distribution)" if kind is FileKind.DISTRIBUTION else ""
        raise ScenarioError(f"file is a {kind.value}, not a scenario{hint}", file=file)
    findings = reading.Findings(deviations=Deviations(strict=options.strict))
    ctx = reading.Context(
        file=file,
        scope=parameters.EMPTY,
        catalogs=Catalogs.empty(scenario_file=file),
        findings=findings,
    )
    ctx, declared = _globals(root, ctx, dict(overrides or {}))
    variables = _variables(root, ctx)
    declared_monitors = monitors.declarations(reading.child(root, "MonitorDeclarations"), ctx)
    catalogs = Catalogs.from_locations(
        root, ctx, path.parent, confinement=confinement, max_bytes=options.max_bytes
    )
    ctx = dataclasses.replace(ctx, catalogs=catalogs, root_scope=ctx.scope)
    header = _header(ctx.require(root, "FileHeader"), ctx)
    if header.description.startswith(rulesets.CARLA_PREFIX):
        # CARLA ScenarioRunner's convention: such a file's positions are in CARLA's frame.
        ctx = dataclasses.replace(ctx, carla_frame=True, right_offsets=True)
        ctx.note(root, "positions read in CARLA's left-handed frame (description 'CARLA:')")
    elif rules.scenario_runner:
        ctx = dataclasses.replace(ctx, right_offsets=True)
        ctx.note(
            root,
            "lateral offsets from the road read positive to the right, as ScenarioRunner places "
            f"them (its rules: {rules.because}); positions stay in OpenDRIVE's frame",
        )
    libraries = MapLibraries.with_user(options.maps)
    road = _road_network(
        reading.child(root, "RoadNetwork"), ctx, path.parent, confinement, libraries
    )
    entities_el = ctx.require(root, "Entities")
    objects = _entities(entities_el, ctx)
    chosen = selections.resolve(reading.all_children(entities_el, "EntitySelection"), objects, ctx)
    ctx = dataclasses.replace(ctx, selections=chosen)
    board = storyboards.storyboard(ctx.require(root, "Storyboard"), ctx)
    return s.Scenario(
        path=path,
        header=header,
        parameters=declared,
        variables=variables,
        monitors=declared_monitors,
        road_network=road,
        entities=objects,
        storyboard=board,
        unsupported_nodes=tuple(findings.unsupported),
        ignored_kinds=tuple(sorted(findings.ignored)),
        notes=tuple(findings.notes),
        deviations=tuple(findings.deviations.found),
        line=root.sourceline,
    )


def _globals(
    root: Element, ctx: reading.Context, overrides: dict[str, str]
) -> tuple[reading.Context, tuple[m.ParameterDeclaration, ...]]:
    block = reading.child(root, "ParameterDeclarations")
    if block is None:
        if overrides:
            raise ctx.error(root, f"overridden parameters are not declared: {', '.join(overrides)}")
        return ctx, ()
    return ctx.declare(block, overrides)


def _variables(root: Element, ctx: reading.Context) -> tuple[m.ParameterDeclaration, ...]:
    block = reading.child(root, "VariableDeclarations")
    if block is None:
        return ()
    entries: list[tuple[str, str, str, int | None]] = []
    for decl in reading.all_children(block, "VariableDeclaration"):
        values = [decl.get(attr) for attr in ("name", "variableType", "value")]
        if any(value is None for value in values):
            raise ctx.error(decl, "VariableDeclaration needs name, variableType and value")
        kind = ctx.parameter_type(decl, "variableType")
        entries.append((ctx.declared_name(decl), kind, str(values[2]), decl.sourceline))
    try:
        _, decls = parameters.declare(entries, ctx.scope)
    except ScenarioError as exc:
        raise ctx.error(block, str(exc.args[0])) from exc
    return decls


def _header(el: Element, ctx: reading.Context) -> s.FileHeader:
    major, minor = ctx.integer(el, "revMajor"), ctx.integer(el, "revMinor")
    if major != 1 or not 0 <= minor <= 3:
        raise ctx.error(el, f"OpenSCENARIO {major}.{minor} is not supported (1.0 to 1.3 are)")
    return s.FileHeader(
        rev_major=major,
        rev_minor=minor,
        date=el.get("date") or "",
        description=el.get("description") or "",
        author=el.get("author") or "",
        line=el.sourceline,
    )


def _road_network(
    el: Element | None,
    ctx: reading.Context,
    base: Path,
    confinement: Confinement,
    libraries: MapLibraries,
) -> s.RoadNetwork:
    if el is None:
        return s.RoadNetwork()
    logic = reading.child(el, "LogicFile")
    if reading.child(el, "SceneGraphFile") is not None:
        ctx.ignore("SceneGraphFile")
    controllers = traffic_signals.controllers(reading.child(el, "TrafficSignals"), ctx)
    if logic is None:
        return s.RoadNetwork(controllers=controllers, line=el.sourceline)
    raw = ctx.string(logic, "filepath")
    if not raw.strip():
        return s.RoadNetwork(controllers=controllers, line=el.sourceline)
    candidates = _road_candidates(raw, base)
    outside = [c for c in candidates if not confinement.allows(c)]
    for target in candidates:
        if target not in outside and target.is_file():
            return s.RoadNetwork(logic_file=target, controllers=controllers, line=el.sourceline)
    # CARLA names its towns ("Town01"); other names come from the user's map libraries.
    name = raw.replace("\\", "/").rsplit("/", 1)[-1]
    found = libraries.find(name)
    if found is not None:
        return s.RoadNetwork(logic_file=found, controllers=controllers, line=el.sourceline)
    if candidates[0] in outside:
        raise ctx.error(
            logic,
            f"road network file {raw!r} refused: {candidates[0]} is {confinement.describe()} "
            f"(and no map {name!r} in the map libraries)",
        )
    looked = ", ".join(str(c) for c in candidates if c not in outside)
    libs = ", ".join(str(f) for f in libraries.folders)
    raise ctx.error(
        logic,
        f"road network file {raw!r} not found (looked for {looked}; map {name!r} in {libs}, "
        f"which hold {', '.join(libraries.names()) or 'no maps'})",
    )


def _road_candidates(raw: str, base: Path) -> list[Path]:
    # Like esmini, fall back to the file name next to the scenario and in a sibling xodr/
    # folder: real files carry absolute paths from their author's machine.
    name = raw.replace("\\", "/").rsplit("/", 1)[-1]
    candidates = [
        (base / raw).resolve(),
        (base / name).resolve(),
        (base.parent / "xodr" / name).resolve(),
    ]
    return list(dict.fromkeys(candidates))


def _entities(el: Element, ctx: reading.Context) -> tuple[e.ScenarioObject, ...]:
    objects: list[e.ScenarioObject] = []
    seen: set[str] = set()
    nodes = list(reading.children(el))
    count = sum(1 for node in nodes if node.tag == "ScenarioObject")
    if count > MAX_ENTITIES:
        raise ctx.error(
            el, f"{count:,} entities, more than {MAX_ENTITIES} (the per-scenario limit)"
        )
    for node in nodes:
        if node.tag == "EntitySelection":
            continue  # resolved once every object is known (readers.selections)
        obj = entities.scenario_object(node, ctx)
        # An inline trailer (and its own, ...) becomes an entity after its tractor, named
        # ``<tractor>+`` as esmini names it (the Trailer element's own name is not used).
        chain: e.ScenarioObject | None = obj
        while chain is not None:
            towed = chain.inline_trailer
            if towed is not None:
                towed = dataclasses.replace(towed, name=f"{chain.name}+")
                chain = dataclasses.replace(chain, trailer=towed.name, inline_trailer=None)
            if chain.name in seen:
                raise ctx.error(node, f"duplicate entity name {chain.name!r}")
            seen.add(chain.name)
            objects.append(chain)
            chain = towed
    names = {obj.name for obj in objects}
    for obj in objects:
        if obj.trailer is not None and obj.trailer not in names:
            raise ScenarioError(
                f"trailer {obj.trailer!r} of {obj.name!r} is not an entity",
                file=ctx.file,
                element="TrailerRef",
                line=obj.line,
            )
    return tuple(objects)
