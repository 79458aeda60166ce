"""Reading ``<EntitySelection>``: a named group of entities usable wherever an entity is.

The standard makes a selection an entity in its own right ("by this name, a selection can be
referenced as an entity"); what it means to the engine is the set of its members. Selections are
resolved once, after the ScenarioObjects are read, into plain entity names: ``EntityRef``
members (an entity or another selection, resolved recursively) and ``ByType`` members (every
object of that type). The readers then expand a selection's name where they read a list of
entities (``TriggeringEntities``, ``Actors``, an Init ``Private``) through
:meth:`~simtest_operator.openscenario.reading.Context.entity_refs`, so nothing downstream knows
selections exist.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import entities as e
from simtest_operator.snapshots import EntityKind
from simtest_operator.xmlsafe import Element

_OBJECT_TYPES = {
    "vehicle": (EntityKind.VEHICLE,),
    "pedestrian": (EntityKind.PEDESTRIAN,),
    "miscellaneous": (EntityKind.MISC_OBJECT,),
    "external": (),
}
"""``ByType objectType`` to entity kinds; ``external`` (ExternalObjectReference) selects none."""


def resolve(
    nodes: Iterable[Element], objects: Iterable[e.ScenarioObject], ctx: reading.Context
) -> Mapping[str, tuple[str, ...]]:
    """The members (entity names, file order, no repeats) of each ``<EntitySelection>`` node.

    A name used by an entity and a selection, a member that is neither, and a selection that
    contains itself are errors naming the element and line.
    """
    objects = tuple(objects)
    names = {obj.name for obj in objects}
    declared: dict[str, Element] = {}
    for node in nodes:
        name = ctx.string(node, "name")
        if name in names or name in declared:
            raise ctx.error(node, f"duplicate entity name {name!r}")
        declared[name] = node
    resolved: dict[str, tuple[str, ...]] = {}

    def members(name: str, path: tuple[str, ...]) -> tuple[str, ...]:
        if name in resolved:
            return resolved[name]
        node = declared[name]
        if name in path:
            raise ctx.error(node, f"entity selection {name!r} contains itself")
        found: list[str] = []
        for member in reading.children(ctx.require(node, "Members")):
            if member.tag == "EntityRef":
                ref = ctx.string(member, "entityRef")
                if ref in declared:
                    found.extend(members(ref, (*path, name)))
                elif ref in names:
                    found.append(ref)
                else:
                    raise ctx.error(member, f"entity {ref!r} of selection {name!r} is not declared")
            elif member.tag == "ByType":
                kind = ctx.string(member, "objectType")
                if kind not in _OBJECT_TYPES:
                    raise ctx.error(member, f"unknown objectType {kind!r}")
                found.extend(obj.name for obj in objects if obj.kind in _OBJECT_TYPES[kind])
            else:
                raise ctx.error(member, "expected EntityRef or ByType")
        resolved[name] = tuple(dict.fromkeys(found))
        return resolved[name]

    for name in declared:
        members(name, ())
    return resolved
