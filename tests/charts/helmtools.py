"""Real helm, helmfile and kubectl for the chart and packaging tests (fixtures + small runners).

The binaries come from ``deploy/devcluster/build.sh`` (Go modules, cached): right after
collection, if a selected test uses one of these fixtures, the build runs once outside every
test timeout (seconds when cached). A failed build fails those tests; it never skips them.
Every tool runs with its caches in a session temp dir, so tests never read ``~/.config/helm``.
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pytest
import yaml

from simtest_operator.devcluster.toolchain import BUILD_SCRIPT, Toolchain, build
from simtest_operator.errors import ToolchainError
from simtest_operator.settings import Settings

REPO = Path(__file__).resolve().parents[2]
OPERATOR_CHART = REPO / "charts" / "simtest-operator"
ROS_CHART = REPO / "charts" / "k8s-ros"
SIMULATOR_CHART = REPO / "charts" / "simtest-simulator"
HELM_FIXTURES = frozenset({"helm", "helmfile", "kubectl"})
COMPONENTS = {"helm": "helm", "helmfile": "helmfile", "kubectl": "kubernetes"}

_built = pytest.StashKey[dict[str, Toolchain | ToolchainError]]()


def build_selected(session: pytest.Session) -> None:
    """``pytest_collection_finish`` body: build the tools the selected tests use."""
    if session.config.option.collectonly or _built in session.config.stash:
        return
    wanted = sorted(
        {
            COMPONENTS[name]
            for item in session.items
            for name in HELM_FIXTURES & set(getattr(item, "fixturenames", ()))
        }
    )
    if not wanted:
        return
    settings = Settings.from_env()
    result: Toolchain | ToolchainError
    try:
        result = build(
            REPO / BUILD_SCRIPT,
            cache_root=settings.cache.root,
            log_file=settings.cache.toolchain / "build.log",
            components=tuple(wanted),
        )
    except ToolchainError as exc:
        result = exc
    session.config.stash[_built] = dict.fromkeys(wanted, result)


def _binary(config: pytest.Config, name: str) -> Path:
    component = COMPONENTS[name]
    result = config.stash.get(_built, {}).get(component)
    if result is None:  # requested dynamically: build now
        settings = Settings.from_env()
        result = build(
            REPO / BUILD_SCRIPT,
            cache_root=settings.cache.root,
            log_file=settings.cache.toolchain / "build.log",
            components=(component,),
        )
    if isinstance(result, ToolchainError):
        raise result
    return result.binary(name)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Tool:
    """One binary with a hermetic environment."""

    path: Path
    env: Mapping[str, str]

    def run(
        self, *args: str | Path, stdin: str | None = None, check: bool = True, cwd: Path = REPO
    ) -> subprocess.CompletedProcess[str]:
        """Run it; on failure (with ``check``) the assertion shows stdout and stderr."""
        result = subprocess.run(
            [str(self.path), *map(str, args)],
            input=stdin,
            capture_output=True,
            text=True,
            env=dict(self.env),
            cwd=cwd,
            timeout=240,
            check=False,
        )
        if check:
            assert result.returncode == 0, (
                f"{self.path.name} {' '.join(map(str, args))} failed ({result.returncode}):\n"
                f"{result.stdout}\n{result.stderr}"
            )
        return result


def _env(home: Path, toolchain_bin: Path) -> dict[str, str]:
    return {
        "PATH": f"{toolchain_bin}{os.pathsep}/usr/bin:/bin",
        "HOME": str(home),
        "HELM_CACHE_HOME": str(home / "helm-cache"),
        "HELM_CONFIG_HOME": str(home / "helm-config"),
        "HELM_DATA_HOME": str(home / "helm-data"),
        "HELM_DRIVER": "configmap",
        "KUBECONFIG": str(home / "no-kubeconfig"),
        "TMPDIR": str(home),
    }


@pytest.fixture(scope="session")
def tools_home(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("tools-home")


@pytest.fixture(scope="session")
def helm(request: pytest.FixtureRequest, tools_home: Path) -> Tool:
    path = _binary(request.config, "helm")
    return Tool(path=path, env=_env(tools_home, path.parent))


@pytest.fixture(scope="session")
def helmfile(request: pytest.FixtureRequest, tools_home: Path, helm: Tool) -> Tool:
    path = _binary(request.config, "helmfile")
    env = _env(tools_home, helm.path.parent)
    env["PATH"] = f"{path.parent}{os.pathsep}{env['PATH']}"
    return Tool(path=path, env=env)


@pytest.fixture(scope="session")
def kubectl(request: pytest.FixtureRequest, tools_home: Path) -> Tool:
    path = _binary(request.config, "kubectl")
    return Tool(path=path, env=_env(tools_home, path.parent))


def template(
    helm: Tool,
    chart: Path,
    *,
    release: str = "simtest-operator",
    namespace: str = "simtest-system",
    values: Mapping[str, Any] | None = None,
    extra: Sequence[str] = (),
    check: bool = True,
) -> subprocess.CompletedProcess[str]:
    """``helm template`` with ``values`` passed as one values file on stdin."""
    args: list[str | Path] = ["template", release, chart, "--namespace", namespace, *extra]
    stdin = None
    if values is not None:
        args += ["--values", "-"]
        stdin = yaml.safe_dump(dict(values))
    return helm.run(*args, stdin=stdin, check=check)


def documents(text: str) -> list[dict[str, Any]]:
    """The non-empty YAML documents of a multi-document text."""
    return [doc for doc in yaml.safe_load_all(text) if doc]


def find(docs: Sequence[Mapping[str, Any]], kind: str, name: str | None = None) -> dict[str, Any]:
    """The one document of ``kind`` (and ``name``)."""
    hits = [
        dict(doc)
        for doc in docs
        if doc.get("kind") == kind and (name is None or doc["metadata"]["name"] == name)
    ]
    assert len(hits) == 1, f"expected one {kind} {name or ''}, found {len(hits)}"
    return hits[0]


def restricted_problems(pod_spec: Mapping[str, Any]) -> list[str]:
    """Violations of the Pod Security "restricted" profile in a pod spec (empty: it meets it)."""
    problems = []
    pod_sc = pod_spec.get("securityContext") or {}
    if pod_sc.get("seccompProfile", {}).get("type") not in ("RuntimeDefault", "Localhost"):
        problems.append("pod seccompProfile")
    for container in [*pod_spec.get("initContainers", []), *pod_spec["containers"]]:
        sc = container.get("securityContext") or {}
        name = container["name"]
        if sc.get("allowPrivilegeEscalation") is not False:
            problems.append(f"{name}: allowPrivilegeEscalation")
        if not (sc.get("runAsNonRoot") or pod_sc.get("runAsNonRoot")):
            problems.append(f"{name}: runAsNonRoot")
        if sc.get("capabilities", {}).get("drop") != ["ALL"]:
            problems.append(f"{name}: capabilities.drop")
        if sc.get("readOnlyRootFilesystem") is not True:
            problems.append(f"{name}: readOnlyRootFilesystem")
        if (sc.get("runAsUser") if "runAsUser" in sc else pod_sc.get("runAsUser")) == 0:
            problems.append(f"{name}: runAsUser 0")
    for volume in pod_spec.get("volumes", []):
        if "hostPath" in volume:
            problems.append(f"volume {volume['name']}: hostPath")
    return problems
