"""The runner's package root is its public entry, and it loads lazily.

Covers: every name in ``runner.__all__`` resolves to the object of the module it is documented to
come from; importing the root loads none of the package's modules (so the pod's entrypoint and
``simtest scenario run`` pay only for what they use), and touching one name loads only that
name's module and what it imports; an unknown name is an AttributeError.
"""

from __future__ import annotations

import importlib
import json
import subprocess
import sys

import pytest

from simtest_operator import runner

LOCAL = {"engine", "search_section_of"}
"""Functions of the package module itself (they pick what to import)."""


def test_every_public_name_resolves_to_its_home() -> None:
    for name in runner.__all__:
        value = getattr(runner, name)
        if name in LOCAL:
            continue
        module, attribute = runner._HOMES[name]
        assert value is getattr(
            importlib.import_module(f"simtest_operator.runner.{module}"), attribute
        )
    assert set(runner.__all__) == {*runner._HOMES, *LOCAL}
    assert set(runner.__all__) <= set(dir(runner))


def test_engine_picks_the_simulator_or_the_test_double() -> None:
    from simtest_operator.runner import engines, fakes

    assert runner.engine("sumo") is engines.execute
    assert runner.engine("fake") is fakes.execute


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'run'"):
        _ = runner.run


def _runner_modules(body: str) -> set[str]:
    code = f"import json, sys\n{body}\nprint(json.dumps(sorted(sys.modules)))"
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    return {m for m in json.loads(done.stdout) if m.startswith("simtest_operator.runner.")}


def test_the_root_loads_only_what_a_caller_touches() -> None:
    assert _runner_modules("import simtest_operator.runner") == set()
    assert _runner_modules("from simtest_operator.runner import summarise") == {
        "simtest_operator.runner.summaries"
    }
