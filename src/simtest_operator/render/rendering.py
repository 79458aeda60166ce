"""Render one environment: Helm values, the simulator pod and the run-specific helmfile.

Pure: the output depends only on the request and the template files — no clock, no cluster, no
random names — so the same request always yields byte-identical files and the same content hash.
The pod is checked against the invariants the operator relies on (one simulator slot, the
restricted Pod Security profile, owner reference, deadline) whatever the template says.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import jinja2
import yaml

from simtest_operator.errors import RenderError
from simtest_operator.render import documents, helmfiles, naming, podchecks, runspecs
from simtest_operator.render.inputs import EnvironmentRequest
from simtest_operator.render.runspecs import RunSpec
from simtest_operator.render.templates import TemplateLibrary

ARTIFACTS_MOUNT = "/artifacts"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RenderedEnvironment:
    """The rendered files of one environment and their digest."""

    values: Mapping[str, Any]
    """Helm values of every release, template defaults merged with the campaign's overrides."""
    pod: Mapping[str, Any]
    """The simulator pod manifest (direct provisioner)."""
    helmfile: str | None
    """Run-specific ``helmfile.yaml`` (when the template has one)."""
    run_spec: RunSpec
    content_hash: str
    """sha256 over values, pod and helmfile; recorded in the SimEnvironment status."""

    def files(self) -> dict[str, str]:
        """File name to text, for ``--out DIR`` and golden tests."""
        out = {
            "values.yaml": documents.to_yaml(self.values),
            "pod.yaml": documents.to_yaml(self.pod),
        }
        if self.helmfile is not None:
            out["helmfile.yaml"] = self.helmfile
        return out


def run_spec_for(request: EnvironmentRequest) -> RunSpec:
    """The run spec the pod's runner receives."""
    return RunSpec(
        campaign=request.campaign,
        environment=request.name,
        attempt=request.attempt,
        scenarios=request.scenarios,
        isolation=request.isolation,
        timeout_seconds=request.timeout_seconds,
        artifacts_dir=f"{ARTIFACTS_MOUNT}/{request.name}",
        artifacts_uri=f"{request.artifacts.uri_prefix}/{request.name}"
        if request.artifacts.uri_prefix
        else "",
        evaluation=request.evaluation,
        sut=request.sut,
        simulator=request.simulator,
        keep_recordings=request.artifacts.keep_recordings,
        databases=request.source_needs.databases,
    )


def render_environment(
    request: EnvironmentRequest, library: TemplateLibrary
) -> RenderedEnvironment:
    """Render ``request`` with its template from ``library``."""
    templates = library.load(request.template)
    run_spec = run_spec_for(request)
    context = _context(request, run_spec)
    base_values = _render_mapping(templates.values, context, what="values.yaml.j2")
    values = documents.deep_merge(base_values, request.values)
    _check_overrides(base_values, values, request)
    context = {**context, "values": values}
    pod = _render_mapping(templates.pod, context, what="pod.yaml.j2")
    podchecks.check_pod(pod, request)
    helmfile = None
    if templates.helmfile is not None:
        release = helmfiles.simulator_release(request, values=values, pod=pod)
        helmfile = _render_text(
            templates.helmfile,
            {**context, "pod": pod, "simulatorRelease": release},
            what="helmfile.yaml.j2",
        )
        helmfiles.check_helmfile(helmfile, pod=pod, request=request)
    digest = documents.content_hash({"values": values, "pod": pod, "helmfile": helmfile})
    return RenderedEnvironment(
        values=values, pod=pod, helmfile=helmfile, run_spec=run_spec, content_hash=digest
    )


_SIMULATOR_UNIT = (
    ("simulator",),
    ("simulator", "image"),
    ("simulator", "resources", "requests", "cpu"),
    ("simulator", "resources", "requests", "memory"),
    ("simulator", "resources", "limits", "cpu"),
    ("simulator", "resources", "limits", "memory"),
)
"""Values the template's simulator pod is built from: an override must not remove them."""


def _lookup(values: Mapping[str, Any], path: tuple[str, ...]) -> Any:
    current: Any = values
    for key in path:
        if not isinstance(current, Mapping):
            return None
        current = current.get(key)
    return current


def _check_overrides(
    base: Mapping[str, Any], merged: Mapping[str, Any], request: EnvironmentRequest
) -> None:
    """The campaign's ``spec.environment.values`` may change the simulator unit, not remove it:
    every key of it the template defines must still hold a value after the merge."""
    lost = [
        ".".join(path)
        for path in _SIMULATOR_UNIT
        if _lookup(base, path) not in (None, "", {}) and _lookup(merged, path) in (None, "", {})
    ]
    if lost:
        raise RenderError(
            f"template {request.template!r}: spec.environment.values removes the simulator "
            f"unit every environment runs ({', '.join(lost)} set to null or emptied); override "
            "its fields with values instead of removing them"
        )


def _owner_reference(request: EnvironmentRequest) -> dict[str, Any]:
    return {
        "apiVersion": request.owner.api_version,
        "kind": request.owner.kind,
        "name": request.owner.name,
        "uid": request.owner.uid,
        "controller": True,
        "blockOwnerDeletion": True,
    }


def _stack_labels(request: EnvironmentRequest) -> dict[str, str]:
    """The operator's ``simtest.dev/*`` labels plus the environment's name: for the objects of
    the environment's other releases (their charts set ``app.kubernetes.io/*`` themselves)."""
    labels = {k: v for k, v in request.labels.items() if k.startswith("simtest.dev/")}
    labels[naming.ENVIRONMENT_LABEL] = request.name
    return dict(sorted(labels.items()))


def _context(request: EnvironmentRequest, run_spec: RunSpec) -> dict[str, Any]:
    env = {
        "name": request.name,
        "namespace": request.namespace,
        "campaign": request.campaign,
        "batch": request.batch,
        "attempt": request.attempt,
        "isolation": request.isolation,
        "labels": dict(sorted(request.labels.items())),
        "owner": {
            "apiVersion": request.owner.api_version,
            "kind": request.owner.kind,
            "name": request.owner.name,
            "uid": request.owner.uid,
        },
        "ownerReference": _owner_reference(request),
        "stackLabels": _stack_labels(request),
        "rosDomainId": naming.ros_domain_id(request.namespace, request.name),
        "chartsDir": request.charts_dir,
        "serviceAccount": request.service_account,
        "image": request.image,
        "requests": dataclasses.asdict(request.requests),
        "limits": dataclasses.asdict(request.limits),
        "timeoutSeconds": request.timeout_seconds,
        "deadlineSeconds": request.deadline_seconds,
        "nodeSelector": dict(sorted(request.node_selector.items())),
        "tolerations": [dict(t) for t in request.tolerations],
        "artifacts": {
            "mountPath": ARTIFACTS_MOUNT,
            "pvc": dataclasses.asdict(request.artifacts.pvc) if request.artifacts.pvc else None,
            "s3": dataclasses.asdict(request.artifacts.s3) if request.artifacts.s3 else None,
            "uriPrefix": request.artifacts.uri_prefix,
        },
        "scenarioVolume": dataclasses.asdict(request.scenario_volume)
        if request.scenario_volume
        else None,
        "scenarioMount": request.scenario_mount,
        "resultsDsn": dataclasses.asdict(request.results_dsn) if request.results_dsn else None,
        "resultsRunKey": request.results_run_key,
        **runspecs.source_context(request.source_needs),
    }
    return {
        "env": env,
        "scenarios": [s.to_json() for s in request.scenarios],
        "scenario": request.scenarios[0].to_json(),
        "sut": dict(request.sut),
        "simulator": dict(request.simulator),
        "evaluation": dict(request.evaluation),
        "runSpec": run_spec.dumps(),
    }


def _render_text(template: jinja2.Template, context: Mapping[str, Any], *, what: str) -> str:
    try:
        return template.render(context)
    except (jinja2.TemplateError, AttributeError, KeyError, TypeError, ValueError) as exc:
        raise RenderError(f"{what}: {exc}") from exc


def _render_mapping(
    template: jinja2.Template, context: Mapping[str, Any], *, what: str
) -> dict[str, Any]:
    text = _render_text(template, context, what=what)
    try:
        loaded = documents.from_yaml(text)
    except yaml.YAMLError as exc:
        raise RenderError(f"{what} did not render to valid YAML: {exc}") from exc
    if loaded is None:
        return {}
    if not isinstance(loaded, dict):
        raise RenderError(f"{what} must render to a mapping, got {type(loaded).__name__}")
    return loaded
