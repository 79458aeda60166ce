"""The run spec: the contract between a rendered simulator pod and ``simtest-runner``.

The operator renders it into the pod (environment variable ``SIMTEST_RUN_SPEC``); the runner
parses it back. Both sides use this one codec, so the format cannot drift between them. It is
plain JSON with camelCase keys; evaluation, SUT and simulator settings travel in their wire form
and the runner validates them through ``api`` like any other manifest input.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping
from typing import Any

from simtest_operator.errors import RenderError
from simtest_operator.render.inputs import ScenarioRef

ENV_VAR = "SIMTEST_RUN_SPEC"
"""Environment variable of the simulator container that carries the run spec."""
FORMAT_VERSION = 1


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RunSpec:
    """What one simulator pod runs and how."""

    campaign: str
    environment: str
    attempt: int
    scenarios: tuple[ScenarioRef, ...]
    isolation: str = "PerScenario"
    timeout_seconds: int = 60
    artifacts_dir: str = "/artifacts"
    artifacts_uri: str = ""
    """Prefix for the artifact URIs in the result; empty means ``file://`` + local path."""
    evaluation: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    sut: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    simulator: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    keep_recordings: bool = True
    """``spec.artifacts.keepRecordings``: False drops each recording once the run is delivered
    (not uploaded, no URI; its digest is still stored). On the wire only when False."""

    def to_json(self) -> dict[str, Any]:
        """JSON-compatible dict."""
        extra: dict[str, Any] = {} if self.keep_recordings else {"keepRecordings": False}
        return {
            "version": FORMAT_VERSION,
            "campaign": self.campaign,
            "environment": self.environment,
            "attempt": self.attempt,
            "scenarios": [s.to_json() for s in self.scenarios],
            "isolation": self.isolation,
            "timeoutSeconds": self.timeout_seconds,
            "artifactsDir": self.artifacts_dir,
            "artifactsUri": self.artifacts_uri,
            "evaluation": dict(self.evaluation),
            "sut": dict(self.sut),
            "simulator": dict(self.simulator),
            **extra,
        }

    def dumps(self) -> str:
        """Canonical text form (sorted keys, no spaces): identical specs give identical text."""
        return json.dumps(self.to_json(), sort_keys=True, separators=(",", ":"))

    @classmethod
    def loads(cls, text: str) -> RunSpec:
        """Parse the text form; a malformed spec is a :class:`RenderError`."""
        try:
            data = json.loads(text)
            if not isinstance(data, dict):
                raise TypeError("run spec must be a JSON object")
            version = int(data.get("version", FORMAT_VERSION))
            if version != FORMAT_VERSION:
                raise ValueError(f"run spec version {version} is not {FORMAT_VERSION}")
            scenarios = tuple(
                ScenarioRef(
                    id=str(s["id"]),
                    source=str(s["source"]),
                    sha256=str(s["sha256"]),
                    overrides={str(k): str(v) for k, v in dict(s.get("overrides", {})).items()},
                )
                for s in data["scenarios"]
            )
            if not scenarios:
                raise ValueError("run spec lists no scenarios")
            return cls(
                campaign=str(data["campaign"]),
                environment=str(data["environment"]),
                attempt=int(data.get("attempt", 1)),
                scenarios=scenarios,
                isolation=str(data.get("isolation", "PerScenario")),
                timeout_seconds=int(data.get("timeoutSeconds", 60)),
                artifacts_dir=str(data.get("artifactsDir", "/artifacts")),
                artifacts_uri=str(data.get("artifactsUri", "")),
                evaluation=dict(data.get("evaluation", {})),
                sut=dict(data.get("sut", {})),
                simulator=dict(data.get("simulator", {})),
                keep_recordings=data.get("keepRecordings", True) is not False,
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise RenderError(f"malformed run spec: {exc}") from exc
