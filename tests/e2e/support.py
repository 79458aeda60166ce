"""Helpers of the end-to-end tests: the operator as a subprocess, campaigns, waiting, reading.

The operator runs as a real ``simtest operator`` process (so it can be killed and restarted and
its logs are kept); the tests talk to the API server with the official client.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import yaml
from kubernetes import client

REPO = Path(__file__).resolve().parents[2]
GROUP, VERSION = "simtest.dev", "v1alpha1"
SMOKE_SCENARIO = REPO / "scenarios" / "smoke" / "cut-in_highway_v25_gap30_dv5.xosc"


def templates_root(tmp: Path) -> Path:
    """A templates root holding the product's ``default`` template and the test-only ``kwok``."""
    root = tmp / "templates"
    root.mkdir(parents=True, exist_ok=True)
    shutil.copytree(REPO / "helm-templates" / "default", root / "default", dirs_exist_ok=True)
    shutil.copytree(Path(__file__).parent / "templates" / "kwok", root / "kwok", dirs_exist_ok=True)
    return root


def scenario_files(folder: Path, names: Sequence[str], *, source: Path = SMOKE_SCENARIO) -> Path:
    """Scenario files with the given names (each a copy of a real smoke scenario, made unique)."""
    folder.mkdir(parents=True, exist_ok=True)
    text = source.read_text(encoding="utf-8")
    for name in names:
        (folder / name).write_text(text + f"<!-- {name} -->\n", encoding="utf-8")
    return folder


class OperatorProcess:
    """``simtest operator`` in a subprocess, restartable; logs collected across restarts."""

    def __init__(
        self,
        *,
        kubeconfig: Path,
        namespace: str,
        templates: Path,
        sources: Path,
        workdir: Path,
        extra_env: Mapping[str, str] | None = None,
    ) -> None:
        self.kubeconfig = kubeconfig
        self.namespace = namespace
        self.templates = templates
        self.sources = sources
        self.workdir = workdir
        self.extra_env = dict(extra_env or {})
        self.process: subprocess.Popen[bytes] | None = None
        self.logs: list[Path] = []

    def start(self, *, kubeconfig: Path | None = None) -> None:
        log = self.workdir / f"operator-{len(self.logs)}.log"
        self.logs.append(log)
        env = {
            **os.environ,
            "SIMTEST_OPERATOR_MISSING_POD_GRACE": "3",
            "SIMTEST_OPERATOR_BACKSTOP_GRACE": "5",
            **self.extra_env,
        }
        command = [
            sys.executable,
            "-c",
            "from simtest_operator.cli.main import main; main()",
            "operator",
            "--namespace",
            self.namespace,
            "--kubeconfig",
            str(kubeconfig or self.kubeconfig),
            "--templates",
            str(self.templates),
            "--sources",
            str(self.sources),
            "--cache",
            str(self.workdir / "cache"),
            "--metrics-port",
            "0",
        ]
        with log.open("wb") as handle:
            self.process = subprocess.Popen(
                command, stdout=handle, stderr=subprocess.STDOUT, env=env
            )

    def stop(self, *, kill: bool = False) -> None:
        process = self.process
        if process is None:
            return
        if process.poll() is None:
            process.send_signal(signal.SIGKILL if kill else signal.SIGTERM)
            try:
                process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        self.process = None

    def alive(self) -> bool:
        return self.process is not None and self.process.poll() is None

    def log_text(self) -> str:
        return "\n".join(
            f"--- {p.name}\n{p.read_text(errors='replace')}" for p in self.logs if p.exists()
        )


def campaign(
    name: str,
    *,
    path: str = "scenarios",
    template: str = "kwok",
    execution: Mapping[str, Any] | None = None,
    values: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    return {
        "apiVersion": f"{GROUP}/{VERSION}",
        "kind": "TestCampaign",
        "metadata": {"name": name},
        "spec": {
            "scenarios": {"sources": [{"path": path}], "include": ["*.xosc"]},
            "environment": {"template": template, "values": dict(values or {})},
            "execution": {"retries": 2, "timeoutSeconds": 30, **dict(execution or {})},
        },
    }


class Cluster:
    """Thin reads and writes the tests need."""

    def __init__(self, api: client.ApiClient, namespace: str) -> None:
        self.api = api
        self.namespace = namespace
        self.custom = client.CustomObjectsApi(api)
        self.core = client.CoreV1Api(api)

    def create(self, body: Mapping[str, Any]) -> None:
        self.custom.create_namespaced_custom_object(
            GROUP, VERSION, self.namespace, "testcampaigns", dict(body)
        )

    def get(self, plural: str, name: str) -> dict[str, Any]:
        return dict(
            self.custom.get_namespaced_custom_object(GROUP, VERSION, self.namespace, plural, name)
        )

    def items(self, plural: str) -> list[dict[str, Any]]:
        reply = self.custom.list_namespaced_custom_object(GROUP, VERSION, self.namespace, plural)
        return list(reply.get("items", []))

    def pods(self) -> list[Any]:
        return list(
            self.core.list_namespaced_pod(
                self.namespace, label_selector="simtest.dev/campaign"
            ).items
        )

    def status(self, name: str) -> dict[str, Any]:
        return dict(self.get("testcampaigns", name).get("status") or {})

    def wait_complete(
        self,
        name: str,
        *,
        timeout: float,
        alive: Callable[[], bool] | None = None,
        during: Callable[[], None] | None = None,
    ) -> dict[str, Any]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            status = self.status(name)
            if any(
                c["type"] == "Complete" and c["status"] == "True"
                for c in status.get("conditions", [])
            ):
                return status
            if alive is not None:
                assert alive(), "the operator process died"
            if during is not None:
                during()
            time.sleep(0.25)
        raise AssertionError(f"campaign {name} not Complete after {timeout}s: {self.status(name)}")

    def results(self, name: str) -> dict[str, dict[str, Any]]:
        """Per-scenario results of all batches; fails on a scenario with two results."""
        found: dict[str, dict[str, Any]] = {}
        for batch in self.items("scenariobatches"):
            if batch["spec"]["campaign"] != name:
                continue
            for result in (batch.get("status") or {}).get("results", []):
                assert result["id"] not in found, f"{result['id']} has two results"
                found[result["id"]] = result
        return found

    def table(self, plural: str) -> tuple[list[str], list[list[Any]]]:
        """Server-side table (what kubectl get prints): column names and rows."""
        reply = self.api.call_api(
            "GET",
            f"{self.api.configuration.host}/apis/{GROUP}/{VERSION}/namespaces/{self.namespace}/{plural}",
            header_params={
                "Accept": "application/json;as=Table;v=v1;g=meta.k8s.io",
                **self._auth(),
            },
        )
        import json

        data = json.loads(reply.read())
        columns = [c["name"] for c in data["columnDefinitions"]]
        return columns, [row["cells"] for row in data["rows"]]

    def _auth(self) -> dict[str, str]:
        token = self.api.configuration.api_key.get(
            "BearerToken"
        ) or self.api.configuration.api_key.get("authorization")
        if not token:
            return {}
        token = str(token)
        return {"Authorization": token if token.startswith("Bearer ") else f"Bearer {token}"}


@contextlib.contextmanager
def running(operator: OperatorProcess) -> Iterator[OperatorProcess]:
    operator.start()
    try:
        yield operator
    finally:
        operator.stop()


def submit(
    manifest: Path, *, namespace: str, kubeconfig: Path, timeout: int, extra: Sequence[str] = ()
) -> subprocess.CompletedProcess[str]:
    """``simtest submit MANIFEST --wait`` as a CI step runs it (a separate process)."""
    return subprocess.run(
        [
            sys.executable,
            "-c",
            "from simtest_operator.cli.main import main; main()",
            "submit",
            str(manifest),
            "--namespace",
            namespace,
            "--kubeconfig",
            str(kubeconfig),
            "--wait",
            "--timeout",
            str(timeout),
            *extra,
        ],
        capture_output=True,
        text=True,
        timeout=timeout + 60,
    )


@contextlib.contextmanager
def identity_kubeconfig(
    documents: Sequence[Mapping[str, Any]],
    *,
    kubectl: Path,
    kubeconfig: Path,
    api: client.ApiClient,
    namespace: str,
    folder: Path,
) -> Iterator[Path]:
    """Apply RBAC ``documents`` (with one ServiceAccount) and yield a kubeconfig that acts as
    that ServiceAccount (a short-lived token); the documents are deleted afterwards."""

    manifest = folder / "rbac.yaml"
    manifest.write_text(yaml.safe_dump_all([dict(d) for d in documents]))
    admin = [str(kubectl), "--kubeconfig", str(kubeconfig)]
    subprocess.run([*admin, "apply", "-f", str(manifest)], check=True, capture_output=True)
    account = next(d for d in documents if d["kind"] == "ServiceAccount")
    token = (
        client.CoreV1Api(api)
        .create_namespaced_service_account_token(
            str(account["metadata"]["name"]), namespace, {"spec": {"expirationSeconds": 3600}}
        )
        .status.token
    )
    config = yaml.safe_load(kubeconfig.read_text())
    config["users"][0]["user"] = {"token": token}
    path = folder / "operator.kubeconfig"
    path.write_text(yaml.safe_dump(config))
    try:
        yield path
    finally:
        subprocess.run(
            [*admin, "delete", "-f", str(manifest), "--ignore-not-found"],
            check=False,
            capture_output=True,
        )


def chart_rbac(
    helm: Path, *, release: str, namespace: str, templates: Sequence[str]
) -> list[dict[str, Any]]:
    """The operator chart's RBAC documents (``templates/<name>.yaml`` each) for one namespace,
    rendered by the real helm."""
    shown = [arg for name in templates for arg in ("--show-only", f"templates/{name}.yaml")]
    text = subprocess.run(
        [
            str(helm),
            "template",
            release,
            str(REPO / "charts" / "simtest-operator"),
            "--namespace",
            namespace,
            "--set",
            f"watch.namespaces={{{namespace}}}",
            *shown,
        ],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    return [d for d in yaml.safe_load_all(text) if d]
