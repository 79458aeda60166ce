"""Reading the storyboard: Init, stories, acts, maneuver groups, maneuvers, events."""

from __future__ import annotations

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import actions as a
from simtest_operator.openscenario.model import scenarios as s
from simtest_operator.openscenario.readers import actions, trigger_conditions
from simtest_operator.xmlsafe import Element

_PRIORITY_ALIASES = {"overwrite": s.Priority.OVERRIDE}


def storyboard(el: Element, ctx: reading.Context) -> s.Storyboard:
    """Read ``<Storyboard>``."""
    return s.Storyboard(
        init=_init(ctx.require(el, "Init"), ctx),
        stories=tuple(_story(story, ctx) for story in reading.all_children(el, "Story")),
        stop_trigger=trigger_conditions.stop_trigger(reading.child(el, "StopTrigger"), ctx),
        line=el.sourceline,
    )


def _init(el: Element, ctx: reading.Context) -> s.Init:
    block = reading.child(el, "Actions")
    if block is None:
        return s.Init(line=el.sourceline)
    global_actions: list[a.GlobalAction] = []
    private: list[s.PrivateInit] = []
    for node in reading.children(block):
        if node.tag == "GlobalAction":
            global_actions.append(actions.global_(node, ctx))
        elif node.tag == "Private":
            # A selection's Private applies to each member (read once per member).
            private.extend(
                s.PrivateInit(
                    entity_ref=ref,
                    actions=tuple(
                        actions.private(pa, ctx)
                        for pa in reading.all_children(node, "PrivateAction")
                    ),
                    line=node.sourceline,
                )
                for ref in ctx.entity_refs([ctx.string(node, "entityRef")])
            )
        elif node.tag == "UserDefinedAction":
            global_actions.append(actions.user_defined(node, ctx))
        else:
            global_actions.append(ctx.unsupported(node, f"unknown Init action {node.tag}"))
    return s.Init(global_actions=tuple(global_actions), private=tuple(private), line=el.sourceline)


def _story(el: Element, ctx: reading.Context) -> s.Story:
    inner, decls = ctx.declarations(el)
    return s.Story(
        name=inner.string(el, "name"),
        acts=tuple(_act(act, inner) for act in reading.all_children(el, "Act")),
        parameters=decls,
        line=el.sourceline,
    )


def _act(el: Element, ctx: reading.Context) -> s.Act:
    groups = tuple(_maneuver_group(g, ctx) for g in reading.all_children(el, "ManeuverGroup"))
    if not groups:
        raise ctx.error(el, "an act needs at least one ManeuverGroup")
    return s.Act(
        name=ctx.string(el, "name"),
        maneuver_groups=groups,
        start_trigger=trigger_conditions.trigger(reading.child(el, "StartTrigger"), ctx),
        stop_trigger=trigger_conditions.stop_trigger(reading.child(el, "StopTrigger"), ctx),
        line=el.sourceline,
    )


def _maneuver_group(el: Element, ctx: reading.Context) -> s.ManeuverGroup:
    actors_el = ctx.require(el, "Actors")
    maneuvers: list[s.Maneuver] = []
    for node in reading.children(el):
        if node.tag == "Maneuver":
            maneuvers.append(maneuver(node, ctx))
        elif node.tag == "CatalogReference":
            entry, inner = ctx.catalogs.find(node, ctx, ("Maneuver",))
            maneuvers.append(maneuver(entry.element, inner))
    return s.ManeuverGroup(
        name=ctx.string(el, "name"),
        maximum_execution_count=ctx.integer(el, "maximumExecutionCount"),
        actors=s.Actors(
            select_triggering_entities=ctx.boolean(actors_el, "selectTriggeringEntities"),
            entity_refs=ctx.entity_refs(
                ctx.string(ref, "entityRef") for ref in reading.all_children(actors_el, "EntityRef")
            ),
            line=actors_el.sourceline,
        ),
        maneuvers=tuple(maneuvers),
        line=el.sourceline,
    )


def maneuver(el: Element, ctx: reading.Context) -> s.Maneuver:
    """Read a ``<Maneuver>`` (inline or catalog entry)."""
    inner, decls = ctx.declarations(el)
    return s.Maneuver(
        name=inner.string(el, "name"),
        events=tuple(_event(ev, inner) for ev in reading.all_children(el, "Event")),
        parameters=decls,
        line=el.sourceline,
    )


def _event(el: Element, ctx: reading.Context) -> s.Event:
    event_actions = tuple(
        actions.storyboard_action(node, ctx) for node in reading.all_children(el, "Action")
    )
    if not event_actions:
        raise ctx.error(el, "an event needs at least one Action")
    count = ctx.opt_integer(el, "maximumExecutionCount", 1)
    return s.Event(
        name=ctx.string(el, "name"),
        priority=ctx.enum(el, "priority", s.Priority, _PRIORITY_ALIASES),
        maximum_execution_count=1 if count is None else count,
        actions=event_actions,
        start_trigger=trigger_conditions.trigger(reading.child(el, "StartTrigger"), ctx),
        line=el.sourceline,
    )
