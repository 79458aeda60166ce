"""Golden files of the default environment template (values, pod, helmfile per case).

Covers: the rendered files equal tests/render/golden/<case>/ byte for byte (rewrite with
``pytest tests/render --update-golden``); rendering twice gives identical bytes and hash; the
hash changes when any input changes.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from simtest_operator import render
from tests.render.cases import CASES, request

REPO = Path(__file__).resolve().parents[2]
GOLDEN = Path(__file__).parent / "golden"
LIBRARY = render.TemplateLibrary(REPO / "helm-templates")


@pytest.mark.parametrize("case", sorted(CASES))
def test_rendering_matches_golden_files(case: str, update_golden: bool) -> None:
    rendered = render.render_environment(CASES[case], LIBRARY)
    files = {**rendered.files(), "hash.txt": rendered.content_hash + "\n"}
    folder = GOLDEN / case
    if update_golden:
        folder.mkdir(parents=True, exist_ok=True)
        for name, text in files.items():
            (folder / name).write_text(text, encoding="utf-8")
    expected = {p.name: p.read_text(encoding="utf-8") for p in folder.iterdir()}
    assert files == expected


def test_rendering_is_deterministic() -> None:
    first = render.render_environment(request(), render.TemplateLibrary(REPO / "helm-templates"))
    second = render.render_environment(request(), render.TemplateLibrary(REPO / "helm-templates"))
    assert first.files() == second.files()
    assert first.content_hash == second.content_hash


@pytest.mark.parametrize(
    "change",
    [
        {"attempt": 3},
        {"timeout_seconds": 61},
        {"values": {"simulator": {"podLabels": {"x": "y"}}}},
        {"simulator": {"seed": 8}},
    ],
)
def test_hash_follows_the_inputs(change: dict[str, object]) -> None:
    base = render.render_environment(request(), LIBRARY)
    changed = render.render_environment(dataclasses.replace(request(), **change), LIBRARY)  # type: ignore[arg-type]
    assert base.content_hash != changed.content_hash
