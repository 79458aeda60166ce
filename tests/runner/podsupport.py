"""Helpers for the simulator-pod tests: a run spec over fake scenario files and a fake engine.

The fake engine (:func:`fake_run_one`) stands in for ``scenario_execution.run_scenario`` inside
``entrypoint.run_job``: it writes the same three files a real run leaves (recording, log, result
file) and returns a verdict chosen by the scenario's ``simtest:fake`` header property, so the
delivery path sees exactly what a pod produces without starting SUMO.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from simtest_operator.render import RunSpec, ScenarioRef
from simtest_operator.runner import delivering, entrypoint, scenario_execution
from simtest_operator.scenarios import sha256_hex
from simtest_operator.settings import Settings
from simtest_operator.verdicts import ScenarioOutcome, Verdict
from tests.runner.support import fake_xosc

VERDICTS = {"pass": Verdict.PASSED, "fail": Verdict.FAILED}


def scenario_refs(folder: Path, behaviours: dict[str, str]) -> tuple[ScenarioRef, ...]:
    """One fake scenario file per name (tagged ``highway``, category ``cut-in``)."""
    folder.mkdir(parents=True, exist_ok=True)
    refs = []
    for name, behaviour in behaviours.items():
        path = folder / f"{name}.xosc"
        path.write_text(fake_xosc(behaviour, tags="highway", category="cut-in"))
        refs.append(
            ScenarioRef(
                id=f"{name}.xosc", source=path.as_uri(), sha256=sha256_hex(path.read_bytes())
            )
        )
    return tuple(refs)


def job(
    tmp_path: Path,
    behaviours: dict[str, str],
    *,
    attempt: int = 1,
    artifacts_uri: str = "",
) -> entrypoint.Job:
    """A job as the pod's runner builds it, artifacts below ``tmp_path/artifacts/env-0``."""
    spec = RunSpec(
        campaign="nightly",
        environment="nightly-b0-s0-a1",
        attempt=attempt,
        scenarios=scenario_refs(tmp_path / "scenarios", behaviours),
        isolation="Reuse" if len(behaviours) > 1 else "PerScenario",
        timeout_seconds=30,
        artifacts_dir=str(tmp_path / "artifacts" / "env-0"),
        artifacts_uri=artifacts_uri,
        sut={"name": "idm-driver", "version": "2.1.0"},
    )
    root = Path(spec.artifacts_dir)
    root.mkdir(parents=True, exist_ok=True)
    settings = Settings.from_env({"SIMTEST_CACHE_DIR": str(tmp_path / "cache")})
    return entrypoint.Job(spec=spec, artifacts=root, settings=settings)


def deliverer(job: entrypoint.Job, env: dict[str, str]) -> delivering.Deliverer:
    """The deliverer the pod's entry point builds for ``job`` in a container environment ``env``
    (its settings read from ``env``, as the entry point reads them)."""
    settings = Settings.from_env({**env, "SIMTEST_CACHE_DIR": str(job.settings.cache.root)})
    job = dataclasses.replace(job, settings=settings)
    return entrypoint.deliverer_for(job, env, run_key=None, deadline=None)


def fake_run_one(request: scenario_execution.RunRequest) -> ScenarioOutcome:
    """Write recording, log and result file like a real run; the verdict from the file header."""
    assert request.output_dir is not None
    out = request.output_dir
    out.mkdir(parents=True, exist_ok=True)
    text = request.scenario.read_text()
    behaviour = "fail" if 'value="fail"' in text else "pass"
    (out / "recording.mcap").write_bytes(b"MCAP" + request.scenario.name.encode() * 100)
    (out / "run.log").write_text(f"ran {request.scenario_id}\n")
    outcome = ScenarioOutcome(
        scenario_id=request.scenario_id or request.scenario.name,
        verdict=VERDICTS[behaviour],
        reason="minTTC 0.9 s < 1.5 s" if behaviour == "fail" else "",
        metrics={"minTTC": 0.9 if behaviour == "fail" else 3.2, "maxDecel": 4.0},
        simulated_seconds=12.0,
        wall_seconds=0.2,
        artifacts={"recording": str(out / "recording.mcap")},
        versions={"simtest": "0.1.0", "sut": "idm-driver 2.1.0"},
    )
    document = outcome.to_json()
    document["artifacts"] = {**outcome.artifacts, "log": str(out / "run.log")}
    (out / "result.json").write_text(json.dumps(document, indent=2))
    return outcome
