"""The one settings root: every topic comes from one read of the environment.

Covers: defaults without variables (cache under ``$HOME/.cache/simtest``, the operator's knobs
as the chart documents them); ``SIMTEST_*`` and ``SIMTEST_OPERATOR_*`` variables land in their
topics; flags of ``simtest operator`` override the variables and a flag not given does not;
``SIMTEST_SECRET_*`` values (local runs) and ``SIMTEST_SOURCE_TOKEN_*`` values (a simulator pod)
are kept but never shown in the repr; the results topic reads ``SIMTEST_RESULTS_*`` and
``SIMTEST_EVALUATE_SUMMARY_FILE`` (an empty variable as unset) and hides its DSNs; the root stays
hashable; a malformed node selector names the variable.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.settings import OperatorSettings, ResultsSettings, Settings


def test_defaults() -> None:
    settings = Settings.from_env({"HOME": "/h"})
    assert settings.cache.root == Path("/h/.cache/simtest")
    assert settings.simulation.seed == 42 and settings.simulation.step_length == 0.05
    assert settings.operator == OperatorSettings()
    assert settings.operator.inputs.templates_dir == Path("helm-templates")
    assert settings.operator.inputs.cache_dir == Path("/tmp/simtest-operator-cache")
    assert settings.operator.inputs.scenario_claim == ""
    assert settings.operator.metrics_port == 8080
    assert settings.secrets == {}


def test_variables_fill_their_topics() -> None:
    settings = Settings.from_env(
        {
            "SIMTEST_CACHE_DIR": "/c",
            "SIMTEST_SEED": "7",
            "SIMTEST_OPERATOR_TEMPLATES": "/t",
            "SIMTEST_OPERATOR_LEADER_ELECTION": "yes",
            "SIMTEST_OPERATOR_HELMFILE_NODE_SELECTOR": "pool=infra, ,zone=a",
            "SIMTEST_OPERATOR_PREFETCH": "0",
            "SIMTEST_OPERATOR_IDENTITY": "",
        }
    )
    assert settings.cache.root == Path("/c") and settings.simulation.seed == 7
    operator = settings.operator
    assert operator.inputs.templates_dir == Path("/t") and operator.leadership.enabled
    assert operator.helmfile.node_selector == {"pool": "infra", "zone": "a"}
    assert operator.pacing.prefetch_per_node == 0
    assert operator.leadership.identity == ""


def test_flags_override_variables() -> None:
    settings = Settings.from_env(
        {"HOME": "/h", "SIMTEST_OPERATOR_METRICS_PORT": "9000", "SIMTEST_OPERATOR_IDENTITY": "a"},
        operator_flags={
            "metrics_port": 0,
            "leadership.identity": None,
            "inputs.sources_dir": Path("/s"),
        },
    )
    assert settings.operator.metrics_port == 0
    assert settings.operator.leadership.identity == "a"
    assert settings.operator.inputs.sources_dir == Path("/s")


def test_secrets_are_kept_but_not_shown() -> None:
    settings = Settings.from_env(
        {"HOME": "/h", "SIMTEST_SECRET_DB_TOKEN": "hunter2", "SIMTEST_SOURCE_TOKEN_0": "s3cret"}
    )
    assert settings.secrets == {"SIMTEST_SECRET_DB_TOKEN": "hunter2"}
    assert settings.source_tokens == {"SIMTEST_SOURCE_TOKEN_0": "s3cret"}
    assert "hunter2" not in repr(settings) and "s3cret" not in repr(settings)


def test_the_results_topic() -> None:
    assert Settings.from_env({"HOME": "/h"}).results == ResultsSettings()
    env = {
        "HOME": "/h",
        "SIMTEST_RESULTS_DATABASE": "",
        "SIMTEST_RESULTS_DSN": " postgresql://runner:pw@db/results\n",
        "SIMTEST_RESULTS_RUN_KEY": "nightly-1",
        "SIMTEST_EVALUATE_SUMMARY_FILE": "/dev/termination-log",
    }
    settings = Settings.from_env(env)
    assert settings.results == ResultsSettings(
        dsn="postgresql://runner:pw@db/results",
        run_key="nightly-1",
        summary_file=Path("/dev/termination-log"),
    )
    assert "pw" not in repr(settings)
    env["SIMTEST_RESULTS_DATABASE"] = "postgresql://ui:pw@db/results"
    assert Settings.from_env(env).results.database == "postgresql://ui:pw@db/results"


def test_the_root_stays_hashable() -> None:
    """Worker tasks carry the settings; the mapping topics do not take part in the hash."""
    env = {"HOME": "/h", "SIMTEST_OPERATOR_HELMFILE_NODE_SELECTOR": "a=b"}
    assert hash(Settings.from_env(env)) == hash(Settings.from_env({"HOME": "/h"}))


def test_malformed_node_selector_names_the_variable() -> None:
    with pytest.raises(ValueError, match="SIMTEST_OPERATOR_HELMFILE_NODE_SELECTOR"):
        Settings.from_env({"HOME": "/h", "SIMTEST_OPERATOR_HELMFILE_NODE_SELECTOR": "novalue"})
