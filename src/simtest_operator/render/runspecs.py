"""The run spec: the contract between a rendered simulator pod and ``simtest-runner``.

The operator renders it into the pod (environment variable ``SIMTEST_RUN_SPEC``); the runner
parses it back. Both sides use this one codec, so the format cannot drift between them. It is
plain JSON with camelCase keys; evaluation, SUT and simulator settings travel in their wire form
and the runner validates them through ``api`` like any other manifest input.

Scenario sources that need more than network reach are part of the contract too: the ConfigMaps
the pod's scenarios name are mounted below :data:`CONFIG_MAP_DIR`, and the scenario databases
holding inline items travel in the spec (``sources``: endpoint, query, variables — never a
token); each Secret key a database needs reaches the runner as the variable
:func:`secret_variables` names, through a ``secretKeyRef``. Fields added since version 1 are on
the wire only when set, so a spec without them reads the same in every runner of version 1.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterable, Mapping
from typing import Any

from simtest_operator.errors import RenderError
from simtest_operator.render.inputs import ScenarioRef
from simtest_operator.scenarios.locating import Needs
from simtest_operator.scenarios.specs import DatabaseSource, GraphqlSource, RestSource, SecretRef
from simtest_operator.settings import SOURCE_TOKEN_PREFIX

ENV_VAR = "SIMTEST_RUN_SPEC"
"""Environment variable of the simulator container that carries the run spec."""
FORMAT_VERSION = 1
CONFIG_MAP_DIR = "/var/run/simtest/configmaps"
"""Where the simulator container finds ConfigMap ``<name>`` (one folder per name)."""


def secret_variables(databases: Iterable[DatabaseSource]) -> dict[SecretRef, str]:
    """The container variable of each distinct Secret key the databases need, in order: computed
    from the run spec alone, so the pod template and the runner agree without naming them twice."""
    refs = dict.fromkeys(d.secret for d in databases if d.secret is not None)
    return {ref: f"{SOURCE_TOKEN_PREFIX}{index}" for index, ref in enumerate(refs)}


def config_map_volumes(names: Iterable[str]) -> list[dict[str, str]]:
    """Volume name and mount path of each ConfigMap (names are DNS labels, volume names must be
    too, so volumes are numbered rather than named after a possibly long ConfigMap name)."""
    return [
        {
            "configMap": name,
            "volume": f"scenario-cm-{index}",
            "mountPath": f"{CONFIG_MAP_DIR}/{name}",
        }
        for index, name in enumerate(names)
    ]


def source_context(needs: Needs) -> dict[str, Any]:
    """``env.scenarioConfigMaps`` (configMap, volume, mountPath) and ``env.scenarioSecrets``
    (variable, name, key) of the pod template."""
    return {
        "scenarioConfigMaps": config_map_volumes(needs.config_maps),
        "scenarioSecrets": [
            {"variable": variable, "name": ref.name, "key": ref.key}
            for ref, variable in secret_variables(needs.databases).items()
        ],
    }


def database_to_json(source: DatabaseSource) -> dict[str, Any]:
    """A database source in the API's wire form (``{"graphql": {...}}`` or ``{"rest": {...}}``)."""
    ref = (
        {"secretRef": {"name": source.secret.name, "key": source.secret.key}}
        if source.secret is not None
        else {}
    )
    if isinstance(source, GraphqlSource):
        return {
            "graphql": {
                "endpoint": source.endpoint,
                "query": source.query,
                "variables": dict(sorted(source.variables.items())),
                **ref,
            }
        }
    return {"rest": {"url": source.url, **ref}}


def database_from_json(data: Any) -> DatabaseSource:
    """Inverse of :func:`database_to_json`; KeyError/TypeError/ValueError when malformed."""
    if not isinstance(data, Mapping) or len(data) != 1:
        raise ValueError("a source must be an object with one field, graphql or rest")
    ((kind, body),) = data.items()
    if not isinstance(body, Mapping):
        raise TypeError(f"source {kind!r} must be an object")
    raw_ref = body.get("secretRef")
    ref = SecretRef(name=str(raw_ref["name"]), key=str(raw_ref["key"])) if raw_ref else None
    if kind == "graphql":
        return GraphqlSource(
            endpoint=str(body["endpoint"]),
            query=str(body["query"]),
            variables={str(k): str(v) for k, v in dict(body.get("variables", {})).items()},
            secret=ref,
        )
    if kind == "rest":
        return RestSource(url=str(body["url"]), secret=ref)
    raise ValueError(f"unknown source kind {kind!r} (graphql or rest expected)")


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
    databases: tuple[DatabaseSource, ...] = ()
    """The campaign's scenario databases the runner asks again for inline items (wire name
    ``sources``; on the wire only when not empty)."""

    def to_json(self) -> dict[str, Any]:
        """JSON-compatible dict."""
        extra: dict[str, Any] = {} if self.keep_recordings else {"keepRecordings": False}
        if self.databases:
            extra["sources"] = [database_to_json(d) for d in self.databases]
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
                databases=tuple(database_from_json(d) for d in data.get("sources", [])),
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise RenderError(f"malformed run spec: {exc}") from exc
