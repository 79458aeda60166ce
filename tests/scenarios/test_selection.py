"""Globs and selectors: ``**`` at any depth incl. the root, root-only patterns, ``?`` and classes
that never cross ``/``, include-then-exclude ordering and sorting, tag and label selection with
``simtest:`` properties and explanations of mismatches."""

from __future__ import annotations

import pytest

from simtest_operator.scenarios import Selector, globbing, selecting


@pytest.mark.parametrize(
    ("path", "pattern", "expected"),
    [
        ("a.xosc", "**/*.xosc", True),
        ("x/y/a.xosc", "**/*.xosc", True),
        ("x/a.xosc", "*.xosc", False),
        ("a.xosc", "*.xosc", True),
        ("cut-in/a.xosc", "cut-in/*", True),
        ("cut-in/x/a.xosc", "cut-in/*", False),
        ("cut-in/x/a.xosc", "cut-in/**", True),
        ("a/b/c/d.xosc", "a/**/d.xosc", True),
        ("a/d.xosc", "a/**/d.xosc", True),
        ("ab.xosc", "a?.xosc", True),
        ("a/.xosc", "a?.xosc", False),
        ("a1.xosc", "a[0-9].xosc", True),
        ("ax.xosc", "a[!0-9].xosc", True),
        ("a/b", "a[!0-9]b", False),
        ("a.xosc.bak", "**/*.xosc", False),
        ("x.y+z.xosc", "x.y+z.xosc", True),
    ],
)
def test_globs(path: str, pattern: str, expected: bool) -> None:
    assert globbing.matches(path, pattern) is expected


def test_include_then_exclude_sorted() -> None:
    files = ["z.xosc", "a/b.xosc", "a/wip/c.xosc", "Catalogs/v.xosc", "road.xodr"]
    kept = selecting.by_globs(files, include=("**/*.xosc",), exclude=("**/wip/**", "Catalogs/**"))
    assert kept == ["a/b.xosc", "z.xosc"]


def test_selector_tags_and_labels() -> None:
    props = {"simtest:tags": "highway, cut-in,,night", "simtest:category": "cut-in", "road": "r1"}
    assert selecting.tags_of(props) == {"highway", "cut-in", "night"}
    assert selecting.matches(Selector(), {})
    assert selecting.matches(Selector(tags=("highway", "night")), props)
    assert not selecting.matches(Selector(tags=("rain",)), props)
    assert selecting.matches(Selector(labels={"category": "cut-in", "road": "r1"}), props)
    assert not selecting.matches(Selector(labels={"category": "cut-out"}), props)
    explained = selecting.explain_mismatch(Selector(tags=("rain",), labels={"road": "r2"}), props)
    assert explained == "missing tags rain; road='r1' (wanted 'r2')"
