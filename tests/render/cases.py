"""Render requests used by the golden tests (one per interesting combination of the shipped
templates, ``default``, ``composed-sut`` and ``ros2``)."""

from __future__ import annotations

from simtest_operator import render
from simtest_operator.scenarios import GraphqlSource, Needs, RestSource, SecretRef

OWNER = render.OwnerRef(
    api_version="simtest.dev/v1alpha1",
    kind="SimEnvironment",
    name="demo-b00003-e007-a2",
    uid="0d1e2f3a",
)
SCENARIO = render.ScenarioRef(
    id="cut-in/fast.xosc",
    source="git+https://example.org/scenarios.git@0123456789abcdef0123456789abcdef01234567#cut-in/fast.xosc",
    sha256="ab" * 32,
    overrides={"EgoSpeed": "30"},
)


def request(**changes: object) -> render.EnvironmentRequest:
    base = render.EnvironmentRequest(
        template="default",
        namespace="ci",
        name="demo-b00003-e007-a2",
        campaign="demo",
        batch="demo-b00003",
        attempt=2,
        labels={
            "simtest.dev/campaign": "demo",
            "simtest.dev/batch": "demo-b00003",
            "simtest.dev/attempt": "2",
        },
        owner=OWNER,
        service_account="demo-simulator",
        scenarios=(SCENARIO,),
        isolation="PerScenario",
        image="registry.example.org/simtest-runner:0.1.0",
        requests=render.Amounts(cpu="500m", memory="1Gi"),
        limits=render.Amounts(cpu="1", memory="2Gi"),
        timeout_seconds=60,
        sut={"name": "idm-driver", "version": "1.2.3", "driverModel": {"timeHeadway": 1.8}},
        simulator={"stepLength": 0.05, "seed": 7},
        evaluation={"criteria": {"collision": "Forbidden", "minTtc": 1.5}},
    )
    import dataclasses

    return dataclasses.replace(base, **changes)  # type: ignore[arg-type]


CASES = {
    "minimal": request(),
    "gpu-pvc-placement": request(
        limits=render.Amounts(cpu="4", memory="8Gi", gpu=1),
        requests=render.Amounts(cpu="4", memory="8Gi", gpu=1),
        node_selector={"simtest.dev/pool": "gpu"},
        tolerations=({"key": "nvidia.com/gpu", "operator": "Exists", "effect": "NoSchedule"},),
        artifacts=render.ArtifactTarget(
            pvc=render.PvcVolume(claim_name="artifacts", sub_path="runs/demo"),
            uri_prefix="pvc://artifacts/runs/demo",
        ),
        results_dsn=render.SecretKey(name="results-db", key="dsn"),
        results_run_key="demo-20261121T101500Z-0a1b2c3d",
        scenario_volume=render.PvcVolume(claim_name="scenarios", read_only=True),
    ),
    "s3-artifacts": request(
        artifacts=render.ArtifactTarget(
            s3=render.S3Target(endpoint="https://s3.example.org", secret_name="artifact-keys"),
            uri_prefix="s3://simtest-artifacts/nightly/demo",
        ),
    ),
    "reuse-values-override": request(
        isolation="Reuse",
        scenarios=(
            SCENARIO,
            render.ScenarioRef(
                id="cut-in/slow.xosc", source="file:///s/slow.xosc", sha256="cd" * 32
            ),
        ),
        sut={"name": "ros-stack", "version": "2.0.0", "image": "registry.example.org/stack:2.0.0"},
        values={
            "simulator": {
                "podAnnotations": {"simtest.dev/fake-duration": "3s"},
                "extraEnv": [{"name": "LOG_LEVEL", "value": "debug"}],
            },
            "sut": {"chartValues": {"resources": {"requests": {"cpu": "250m"}}}},
        },
    ),
    "scenario-sources": request(
        isolation="Reuse",
        scenarios=(
            render.ScenarioRef(id="a.xosc", source="configmap:suite-a/a.xosc", sha256="01" * 32),
            render.ScenarioRef(id="b.xosc", source="configmap:suite-b/b.xosc", sha256="02" * 32),
            render.ScenarioRef(
                id="c.xosc", source="graphql+https://db.example/graphql#c", sha256="03" * 32
            ),
            render.ScenarioRef(
                id="d.xosc", source="rest+https://db.example/api?suite=x#d", sha256="04" * 32
            ),
        ),
        source_needs=Needs(
            config_maps=("suite-a", "suite-b"),
            databases=(
                GraphqlSource(
                    endpoint="https://db.example/graphql",
                    query="query($s: String) { scenarios(suite: $s) { id content } }",
                    variables={"s": "x"},
                    secret=SecretRef(name="scenario-db", key="token"),
                ),
                RestSource(
                    url="https://db.example/api?suite=x",
                    secret=SecretRef(name="scenario-db", key="token"),
                ),
            ),
        ),
    ),
    "composed-sut": request(
        template="composed-sut",
        sut={
            "name": "simtest-sut-go",
            "version": "1.0.0",
            "image": "ghcr.io/simtest-dev/simtest-sut-go:0.1.0",
            "config": {"profile": "urban"},
            "external": {
                "endpoint": "127.0.0.1:7460",
                "port": 7461,
                "startupTimeoutSeconds": 30,
                "env": {"SUT_LOG": "info"},
            },
        },
        values={"stack": {"resources": {"requests": {"cpu": "250m"}}}},
    ),
    "ros2-minimal": request(template="ros2"),
    "ros2-overrides": request(
        template="ros2",
        sut={"name": "acme-stack", "version": "3.1.0", "image": "ghcr.io/acme/stack:3.1.0"},
        values={
            "ros": {"domainId": 42, "rmw": "rmw_fastrtps_cpp", "unicastPeers": False},
            "stack": {
                "components": {
                    "control": {"enabled": False},
                    "planning": {
                        "chartValues": {
                            "args": ["ros2", "launch", "acme_planning", "planner.launch.py"],
                            "resources": {"requests": {"cpu": "1"}},
                        }
                    },
                },
            },
        },
    ),
    "ros2-stack-in-pod": request(
        template="ros2",
        sut={
            "name": "acme-stack",
            "version": "3.1.0",
            "image": "ghcr.io/acme/stack:3.1.0",
            "external": {
                "image": "ghcr.io/simtest-dev/simtest-runner:0.1.0",
                "command": ["simtest-ros2-bridge", "--port", "{port}"],
                "startupTimeoutSeconds": 120,
            },
        },
        values={
            "stack": {
                "placement": "pod",
                "components": {
                    "perception": {"enabled": False},
                    "planning": {"enabled": False},
                    "evaluator": {"enabled": False},
                    "control": {
                        "chartValues": {
                            "command": ["ros2", "launch"],
                            "args": ["acme_control", "control.launch.py"],
                            "env": {"ACME_PROFILE": "highway"},
                        }
                    },
                },
            },
        },
    ),
}
