"""The hot paths start lean: what a scenario run has loaded at its first step, and a warm pod.

Covers, on real SUMO runs of a smoke scenario in fresh interpreters: ``simtest scenario run`` and
the ``simtest-runner`` entrypoint reach their first simulation step without omega-prime, its
data-frame stack, betterosi, matplotlib, the Kubernetes client, PostgreSQL, S3, rich, or
libsumo's traci/sumolib façade, and the CLI run never loads omega-prime at all; a ``Reuse`` pod
loads libsumo once, in the parent, and every scenario runs in a worker forked with it already
loaded; the reset check refuses to fork from a parent that has a simulation loaded. Timings are
not asserted here: ``bench/startup.py`` measures them.
"""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from pathlib import Path

import pytest

from simtest_operator.render import RunSpec, ScenarioRef
from simtest_operator.runner import entrypoint
from simtest_operator.sim import netcache
from simtest_operator.sim.backends import BackendConfig
from simtest_operator.sim.sumo import SumoBackend

SMOKE = Path(__file__).resolve().parents[2] / "scenarios" / "smoke"
SCENARIO = SMOKE / "hard-braking_rural_v15_thw2_d4.xosc"
NEVER_BEFORE_FIRST_STEP = frozenset(
    {
        *("omega_prime", "betterosi", "pyarrow", "polars", "pandas", "matplotlib"),
        *("kopf", "kubernetes", "psycopg", "boto3", "botocore", "rich", "traci", "sumolib"),
        "pyproj",
    }
)

_PROBE = """
import json, sys
from simtest_operator.runner import scenario_execution

def _at_first_step(*args, **kwargs):
    sys.stderr.write("first-step " + json.dumps(sorted(sys.modules)) + "\\n")
    return plain(*args, **kwargs)

plain, scenario_execution._loop = scenario_execution._loop, _at_first_step
try:
    {body}
except SystemExit:
    pass
finally:
    sys.stderr.write("at-exit " + json.dumps(sorted(sys.modules)) + "\\n")
"""


def packages_loaded(body: str, env: dict[str, str] | None = None) -> dict[str, set[str]]:
    """Top-level packages loaded at the first step and at exit of ``body`` in a fresh process
    (and, under ``<label>-modules``, every module)."""
    done = subprocess.run(
        [sys.executable, "-c", _PROBE.replace("{body}", body)],
        capture_output=True,
        text=True,
        timeout=240,
        check=False,
        env=env,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    found: dict[str, set[str]] = {}
    for line in done.stderr.splitlines():
        label, _, modules = line.partition(" ")
        if label in ("first-step", "at-exit"):
            found[f"{label}-modules"] = set(json.loads(modules))
            found[label] = {m.split(".")[0] for m in found[f"{label}-modules"]}
    return found


def spec_for(scenarios: list[Path], artifacts: Path, isolation: str) -> RunSpec:
    refs = tuple(
        ScenarioRef(id=p.name, source=p.as_uri(), sha256=hashlib.sha256(p.read_bytes()).hexdigest())
        for p in scenarios
    )
    return RunSpec(
        campaign="startup",
        environment="e0",
        attempt=1,
        scenarios=refs,
        isolation=isolation,
        timeout_seconds=60,
        artifacts_dir=str(artifacts),
    )


@pytest.mark.slow
def test_scenario_run_reaches_its_first_step_lean(tmp_path: Path) -> None:
    found = packages_loaded(
        "from simtest_operator.cli.main import main\n"
        f"    sys.argv = ['simtest', 'scenario', 'run', {str(SCENARIO)!r}, "
        f"'--out', {str(tmp_path / 'out')!r}]\n"
        "    main()"
    )
    assert found["first-step"] & NEVER_BEFORE_FIRST_STEP == set()
    assert {"libsumo", "numpy"} <= found["first-step"]
    assert found["at-exit"] & {"omega_prime", "betterosi", "pyarrow", "polars"} == set()
    assert (tmp_path / "out" / "recording.mcap").is_file()


@pytest.mark.slow
def test_the_runner_reaches_its_first_step_lean(tmp_path: Path) -> None:
    spec = spec_for([SCENARIO], tmp_path / "artifacts", "PerScenario")
    log = tmp_path / "termination-log"
    found = packages_loaded(
        "from simtest_operator.runner.launch import main\n"
        f"    sys.argv = ['simtest-runner', '--spec', {spec.dumps()!r}, "
        f"'--termination-log', {str(log)!r}]\n"
        "    main()",
        env={"PATH": "/usr/bin:/bin", "SIMTEST_CACHE_DIR": str(tmp_path / "cache")},
    )
    assert found["first-step"] & NEVER_BEFORE_FIRST_STEP == set()
    # The pod validates three wire models of its run spec and renders nothing.
    assert found["first-step"] & {"jinja2", "yaml"} == set()
    assert {"simtest_operator.api.v1alpha1.kinds", "simtest_operator.render.rendering"} & found[
        "first-step-modules"
    ] == set()
    assert found["at-exit"] & {"omega_prime", "betterosi", "pyarrow", "polars"} == set()
    assert json.loads(log.read_text())["verdict"] == "Passed"


_WARM_POD = """
import json, os, sys
from pathlib import Path
from simtest_operator.render import RunSpec
from simtest_operator.runner import entrypoint, scenario_execution
from simtest_operator.settings import Settings
from simtest_operator.sim import sumo

plain = scenario_execution.run_scenario

def traced(request):
    report = plain(request)
    seen = {"pid": os.getpid(), "warm": warm}
    Path(request.output_dir, "seen.json").write_text(json.dumps(seen))
    return report

def started(request):
    global warm
    warm = "libsumo.libsumo" in sys.modules  # before this scenario touched the simulator
    return traced(request)

scenario_execution.run_scenario = started
spec = RunSpec.loads(sys.argv[1])
job = entrypoint.Job(spec=spec, artifacts=Path(spec.artifacts_dir),
                     settings=Settings.from_env({"SIMTEST_CACHE_DIR": sys.argv[2]}))
attempts = entrypoint.run_job(job)
print(json.dumps({"pid": os.getpid(), "running": sumo.running(),
                  "verdicts": [a.outcome.verdict.value for a in attempts]}))
"""


@pytest.mark.slow
def test_a_warm_pod_loads_libsumo_once_and_forks_with_it(tmp_path: Path) -> None:
    scenarios = [SCENARIO, SMOKE / "cut-in_highway_v30_gap8_dv12.xosc"]
    spec = spec_for(scenarios, tmp_path / "artifacts", "Reuse")
    done = subprocess.run(
        [sys.executable, "-c", _WARM_POD, spec.dumps(), str(tmp_path / "cache")],
        capture_output=True,
        text=True,
        timeout=240,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    parent = json.loads(done.stdout.strip().splitlines()[-1])
    assert parent["verdicts"] == ["Passed", "Failed"]
    assert parent["running"] is False
    seen = [
        json.loads((tmp_path / "artifacts" / p.name / "seen.json").read_text()) for p in scenarios
    ]
    assert all(s["warm"] for s in seen)
    pids = {s["pid"] for s in seen}
    assert len(pids) == 2 and parent["pid"] not in pids


def test_no_fork_from_a_parent_with_a_simulation_loaded(tmp_path: Path) -> None:
    net = netcache.ensure_net(SMOKE.parent / "roads" / "rural_curved.xodr", cache_dir=tmp_path)
    backend = SumoBackend()
    backend.start(BackendConfig(net_file=net.path))
    try:
        assert entrypoint.reset_problem() == "the parent process has a SUMO simulation loaded"
    finally:
        backend.close()
    assert entrypoint.reset_problem() is None
