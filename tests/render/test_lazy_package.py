"""``render`` loads its modules on first use: the simulator pod reads its run spec without the
renderer.

Covers: every name in ``render.__all__`` resolves to the object of the module it is listed
under; the run spec and the message codec load neither the renderer nor Jinja or YAML; an
unknown name is an AttributeError.
"""

from __future__ import annotations

import importlib
import json
import subprocess
import sys

import pytest

from simtest_operator import render


def test_every_public_name_resolves_to_its_module() -> None:
    for name in render.__all__:
        module = importlib.import_module(f"simtest_operator.render.{render._MODULES[name]}")
        assert getattr(render, name) is getattr(module, name)
    assert set(render.__all__) == set(render._MODULES)


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'render'"):
        _ = render.render


def test_the_run_spec_loads_without_the_renderer() -> None:
    code = (
        "import json, sys\n"
        "from simtest_operator.render import RunSpec, messages\n"
        "print(json.dumps(sorted(sys.modules)))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    loaded = set(json.loads(done.stdout))
    assert "simtest_operator.render.runspecs" in loaded
    assert {"simtest_operator.render.rendering", "jinja2", "yaml"} & loaded == set()
