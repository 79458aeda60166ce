"""Reading OpenSCENARIO 1.3 ``MonitorDeclarations`` and ``SetMonitorAction``."""

from __future__ import annotations

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import monitors as mon
from simtest_operator.xmlsafe import Element


def declarations(el: Element | None, ctx: reading.Context) -> tuple[mon.MonitorDeclaration, ...]:
    """Read the optional ``<MonitorDeclarations>`` of the scenario; a name declared twice is an
    error."""
    if el is None:
        return ()
    found: dict[str, mon.MonitorDeclaration] = {}
    for node in reading.all_children(el, "MonitorDeclaration"):
        name = ctx.string(node, "name")
        if name in found:
            raise ctx.error(node, f"monitor {name!r} is declared twice")
        found[name] = mon.MonitorDeclaration(
            name=name, value=ctx.boolean(node, "value"), line=node.sourceline
        )
    return tuple(found.values())


def set_monitor(el: Element, ctx: reading.Context) -> mon.SetMonitorAction:
    """Read ``<SetMonitorAction monitorRef value>`` (the engine checks the monitor exists)."""
    return mon.SetMonitorAction(
        monitor_ref=ctx.string(el, "monitorRef"),
        value=ctx.boolean(el, "value"),
        line=el.sourceline,
    )
