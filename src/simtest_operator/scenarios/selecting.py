"""Selection: include/exclude globs over source paths, then tags and labels from file headers.

Pure functions over names and header properties; reading the headers is the OpenSCENARIO layer's
job (``openscenario.headers``), done by the caller only for the files the globs kept.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from simtest_operator.scenarios import globbing
from simtest_operator.scenarios.specs import Selector

TAGS_PROPERTY = "simtest:tags"
"""FileHeader property with comma-separated tags."""
PROPERTY_PREFIX = "simtest:"


def by_globs(
    paths: Iterable[str], *, include: tuple[str, ...], exclude: tuple[str, ...]
) -> list[str]:
    """The paths matching some include pattern and no exclude pattern, sorted."""
    return sorted(
        path
        for path in paths
        if globbing.matches_any(path, include) and not globbing.matches_any(path, exclude)
    )


def tags_of(properties: Mapping[str, str]) -> frozenset[str]:
    """The tags listed in ``simtest:tags`` (comma-separated, blanks ignored)."""
    raw = properties.get(TAGS_PROPERTY, "")
    return frozenset(tag.strip() for tag in raw.split(",") if tag.strip())


def label_value(properties: Mapping[str, str], key: str) -> str | None:
    """The value of label ``key``: the property ``key`` itself, else ``simtest:<key>``."""
    if key in properties:
        return properties[key]
    return properties.get(PROPERTY_PREFIX + key)


def matches(selector: Selector, properties: Mapping[str, str]) -> bool:
    """Whether a file with these FileHeader properties satisfies ``selector``."""
    if not set(selector.tags) <= tags_of(properties):
        return False
    return all(label_value(properties, key) == value for key, value in selector.labels.items())


def explain_mismatch(selector: Selector, properties: Mapping[str, str]) -> str:
    """Why ``properties`` do not satisfy ``selector`` (for a ``--explain`` style listing)."""
    missing = sorted(set(selector.tags) - tags_of(properties))
    reasons = [f"missing tags {', '.join(missing)}"] if missing else []
    for key, value in selector.labels.items():
        actual = label_value(properties, key)
        if actual != value:
            reasons.append(f"{key}={actual!r} (wanted {value!r})")
    return "; ".join(reasons) or "matches"
