"""Invariants every rendered helmfile must meet, whatever its template or the overrides say.

The ``provisioner: Helmfile`` path applies the helmfile instead of creating the pod, and the
operator must then find exactly the pod the direct path would have created (same name, labels,
ownerReferences, one simulator unit). So the helmfile must install the simulator through the
``simtest-simulator`` chart, once, with the rendered pod inlined *verbatim* as its ``pod`` value
(that chart emits it unchanged but for the release namespace, which must be the environment's).
Every release lives in the environment's namespace under a valid, unique Helm release name.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

import yaml

from simtest_operator.errors import RenderError
from simtest_operator.render import documents, naming
from simtest_operator.render.inputs import EnvironmentRequest

SIMULATOR_CHART = "simtest-simulator"
"""Chart (folder name under ``global.chartsDir``) that installs the rendered simulator pod."""
SIMULATOR_COMPONENT = "sim"
_RELEASE = re.compile(r"^[a-z0-9]([-a-z0-9]*[a-z0-9])?$")


def simulator_release(
    request: EnvironmentRequest, *, values: Mapping[str, Any], pod: Mapping[str, Any]
) -> dict[str, Any]:
    """The helmfile release that installs the rendered pod (``simulatorRelease`` in templates).

    Built here, not by each template, so the contract holds by construction: chart
    ``<global.chartsDir>/simtest-simulator``, the environment's namespace, ``pod`` verbatim.
    """
    global_values = values.get("global")
    charts_dir = (
        global_values.get("chartsDir", request.charts_dir)
        if isinstance(global_values, Mapping)
        else request.charts_dir
    )
    return {
        "name": naming.release_name(request.name, SIMULATOR_COMPONENT),
        "namespace": request.namespace,
        "chart": f"{str(charts_dir).rstrip('/')}/{SIMULATOR_CHART}",
        "labels": {
            "simtest.dev/campaign": request.campaign,
            naming.ENVIRONMENT_LABEL: request.name,
            "component": "simulator",
        },
        "values": [
            {
                "global": dict(global_values) if isinstance(global_values, Mapping) else {},
                "pod": pod,
            }
        ],
    }


def check_helmfile(text: str, *, pod: Mapping[str, Any], request: EnvironmentRequest) -> None:
    """Raise :class:`RenderError` listing every violated invariant of a rendered helmfile."""
    try:
        loaded = documents.from_yaml(text)
    except yaml.YAMLError as exc:
        raise _error(request, [f"not valid YAML: {exc}"]) from exc
    releases = loaded.get("releases") if isinstance(loaded, Mapping) else None
    if not isinstance(releases, list) or not releases:
        raise _error(request, ["it must hold a non-empty `releases:` list"])
    problems: list[str] = []
    names: set[str] = set()
    simulators: list[Mapping[str, Any]] = []
    for index, release in enumerate(releases):
        if not isinstance(release, Mapping):
            problems.append(f"releases[{index}] must be a mapping")
            continue
        name = str(release.get("name", ""))
        if not _RELEASE.match(name) or len(name) > naming.MAX_RELEASE:
            problems.append(
                f"release {name!r}: a Helm release name is a DNS label of at most "
                f"{naming.MAX_RELEASE} characters"
            )
        if name in names:
            problems.append(f"release {name!r} appears twice")
        names.add(name)
        if release.get("namespace") != request.namespace:
            problems.append(f"release {name!r} must be installed in {request.namespace!r}")
        chart = str(release.get("chart", ""))
        if not chart:
            problems.append(f"release {name!r} names no chart")
        if chart.rstrip("/").rsplit("/", 1)[-1] == SIMULATOR_CHART:
            simulators.append(release)
    if len(simulators) != 1:
        problems.append(
            f"exactly one release must use the {SIMULATOR_CHART} chart (found "
            f"{len(simulators)}): the simulator unit is what the operator waits for"
        )
    else:
        problems.extend(_simulator_problems(simulators[0], pod))
    if problems:
        raise _error(request, problems)


def _simulator_problems(release: Mapping[str, Any], pod: Mapping[str, Any]) -> list[str]:
    entries = release.get("values") or []
    if not isinstance(entries, list) or not all(isinstance(e, Mapping) for e in entries):
        return ["the simulator release's values must be inline mappings (the file alone runs)"]
    merged: dict[str, Any] = {}
    for entry in entries:
        merged = documents.deep_merge(merged, entry)
    if documents.canonical_json(merged.get("pod")) != documents.canonical_json(pod):
        return [
            "the simulator release must pass the rendered pod unchanged as its `pod` value "
            "(the operator finds it by that name, labels and owner reference)"
        ]
    return []


def _error(request: EnvironmentRequest, problems: list[str]) -> RenderError:
    return RenderError(
        f"template {request.template!r} renders a helmfile the operator cannot use: "
        + "; ".join(problems)
    )
