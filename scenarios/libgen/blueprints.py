"""What a template returns: everything about one concrete scenario except its file layout.

A blueprint keeps the parameter values, the tags and the storyboard pieces together so the
writer can turn it into a stand-alone .xosc file and the suite can check it (road length,
names, tag vocabulary) before anything is written.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from scenariogeneration import xosc

from libgen import roads

CATEGORIES = (
    "following",
    "cut-in",
    "cut-out",
    "hard-braking",
    "lane-change",
    "merge",
    "ltap",
    "pedestrian-crossing",
)
"""The eight templates of the suite; each is a folder under `library/` and the
`simtest:category` value."""

SEARCH_CATEGORIES = ("pedestrian-turn-back",)
"""Templates outside the suite: logical scenarios for the search benchmark (bench/search.py),
a folder under `library/` each, excluded from the 200-scenario campaigns."""

INTERACTIONS = {
    "following": "longitudinal",
    "hard-braking": "longitudinal",
    "cut-out": "longitudinal",
    "cut-in": "lateral",
    "lane-change": "lateral",
    "merge": "lateral",
    "ltap": "crossing",
    "pedestrian-crossing": "crossing",
    "pedestrian-turn-back": "crossing",
}
"""Which way the critical actor approaches the ego's path."""

FEATURES = {
    "highway_straight": "straight",
    "rural_curved": "curve",
    "highway_merge": "on-ramp",
    "junction_4way": "junction",
}
"""Road-feature tag per road network."""


@dataclass(frozen=True, slots=True, kw_only=True)
class Blueprint:
    """One concrete scenario, ready to be written."""

    category: str
    """Template name, one of CATEGORIES."""
    road: roads.RoadNet
    """Road network the scenario runs on."""
    stem: str
    """File name without extension, unique within the category."""
    description: str
    """One sentence for the FileHeader."""
    parameters: tuple[tuple[str, float], ...]
    """ParameterDeclarations in order: (name, value); all are doubles."""
    duration: float
    """Simulated seconds until the storyboard stop trigger fires."""
    tags: tuple[str, ...]
    """Coverage tags, written comma-separated to `simtest:tags`."""
    entities: xosc.Entities
    init: xosc.Init
    stories: tuple[xosc.Story, ...]


def speed_band(speed: float) -> str:
    """Coarse ego-speed tag for coverage tables (m/s: < 12 low, <= 25 mid, above high)."""
    if speed < 12.0:
        return "low-speed"
    return "mid-speed" if speed <= 25.0 else "high-speed"


def tags_for(
    category: str, road: roads.RoadNet, ego_speed: float, extra: Sequence[str] = ()
) -> tuple[str, ...]:
    """The standard tag set: category, road kind, road feature, interaction, actor, speed band."""
    actor = "pedestrian" if category.startswith("pedestrian-") else "vehicle"
    base = (
        category,
        road.kind,
        FEATURES[road.name],
        INTERACTIONS[category],
        actor,
        speed_band(ego_speed),
    )
    return base + tuple(extra)


def number(value: float) -> str:
    """Short, stable text for a parameter value (30.0 -> '30', 1.25 -> '1.25')."""
    text = f"{value:.2f}".rstrip("0").rstrip(".")
    return "0" if text == "-0" else text


def check_reach(blueprint: Blueprint, entity: str, start: float, speed: float) -> None:
    """Fail when an entity driving at `speed` would leave the road before the stop trigger."""
    end = start + speed * blueprint.duration
    if end > blueprint.road.length - 5.0:
        raise ValueError(
            f"{blueprint.stem}: {entity} would reach s={end:.0f} m on {blueprint.road.name} "
            f"(length {blueprint.road.length:.0f} m); shorten the scenario or start earlier"
        )
