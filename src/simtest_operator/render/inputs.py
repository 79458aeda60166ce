"""What rendering one environment needs, as plain immutable values.

``render`` sits beside ``api`` in the layer map and must not import it (nor pydantic): the operator
converts a campaign's wire spec into these dataclasses and passes them in, so rendering stays a
pure function of values that tests can build by hand (STYLE rule 7).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from simtest_operator.scenarios.locating import Needs
from simtest_operator.scenarios.pinned import PinnedScenario

SIMULATOR_RESOURCE = "simtest.dev/simulator"
"""Extended resource: one unit is one simulator slot on a node."""
GPU_RESOURCE = "nvidia.com/gpu"
CHARTS_DIR = "/opt/simtest/charts"
"""Where the helmfile image keeps ``charts/``: the default root of the charts a rendered helmfile
refers to. Must equal ``packaging.IMAGE_CHARTS_DIR`` (``render`` may not import ``packaging``;
``tests/render/test_helmfiles.py`` checks they agree)."""


ScenarioRef = PinnedScenario
"""One frozen scenario the environment runs: the pinned entry of the campaign's frozen list
(id, source URI, sha256, parameter overrides), with the same wire form."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class OwnerRef:
    """The object that owns the rendered pod (its SimEnvironment)."""

    api_version: str
    kind: str
    name: str
    uid: str


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Amounts:
    """cpu / memory quantities and a GPU count."""

    cpu: str
    memory: str
    gpu: int = 0


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class PvcVolume:
    """A PersistentVolumeClaim mounted into the simulator pod."""

    claim_name: str
    sub_path: str = ""
    read_only: bool = False


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class S3Target:
    """An S3-compatible endpoint the runner uploads to, keys from a Secret (never inlined)."""

    endpoint: str
    secret_name: str
    """Secret with ``AWS_ACCESS_KEY_ID`` and ``AWS_SECRET_ACCESS_KEY``."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ArtifactTarget:
    """Where the runner writes artifacts: a PVC folder, an S3 bucket, or the pod's scratch space."""

    pvc: PvcVolume | None = None
    s3: S3Target | None = None
    uri_prefix: str = ""
    """Prefix of the artifact URIs the runner reports (``pvc://claim/sub/campaign`` or
    ``s3://bucket/prefix/campaign``); the environment's name is appended."""
    keep_recordings: bool = True
    """False: the runner drops each recording after the run (``spec.artifacts.keepRecordings``)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SecretKey:
    """A key of a Secret, exposed to the runner as an environment variable (never inlined)."""

    name: str
    key: str


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EnvironmentRequest:
    """Everything one SimEnvironment renders from: identity, scenarios, settings, placement."""

    template: str
    """Folder under the templates root, e.g. ``default``."""
    namespace: str
    name: str
    """SimEnvironment name; the pod and the artifact folder take it too."""
    campaign: str
    batch: str
    attempt: int
    labels: Mapping[str, str]
    """Labels the operator selects its pods by (campaign, batch, environment, attempt)."""
    owner: OwnerRef
    service_account: str
    scenarios: tuple[ScenarioRef, ...]
    isolation: str
    """``PerScenario`` or ``Reuse``."""
    image: str
    requests: Amounts
    limits: Amounts
    timeout_seconds: int
    """Wall-clock limit of one scenario."""
    node_selector: Mapping[str, str] = dataclasses.field(default_factory=dict)
    tolerations: tuple[Mapping[str, Any], ...] = ()
    """Pod tolerations in core/v1 wire form."""
    artifacts: ArtifactTarget = dataclasses.field(default_factory=ArtifactTarget)
    scenario_volume: PvcVolume | None = None
    """Read-only volume holding ``file://`` scenario sources, mounted at ``scenario_mount``."""
    scenario_mount: str = "/scenarios"
    source_needs: Needs = dataclasses.field(default_factory=Needs)
    """What the pod's runner needs to fetch its scenarios beyond network reach: the ConfigMaps
    it reads keys of (mounted read-only) and the databases it asks again (in the run spec, their
    tokens through ``secretKeyRef`` variables)."""
    results_dsn: SecretKey | None = None
    results_run_key: str = ""
    """The campaign's run in the results database (``SIMTEST_RESULTS_RUN_KEY`` of the pod)."""
    """Results database DSN, handed to the runner through a secretKeyRef."""
    sut: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    """System-under-test config in wire form (camelCase)."""
    simulator: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    """Simulator settings in wire form (camelCase)."""
    evaluation: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    """Evaluation spec in wire form (criteria plus per-scenario overrides)."""
    values: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    """The campaign's Helm value overrides, deep-merged over the template's values."""
    charts_dir: str = CHARTS_DIR
    """Root of the charts the helmfile refers to (``values.global.chartsDir``); tests and
    ``simtest render --charts-dir`` point it at a checkout's ``charts/``."""

    @property
    def deadline_seconds(self) -> int:
        """``activeDeadlineSeconds``: every queued scenario's limit plus a start-up allowance."""
        return self.timeout_seconds * len(self.scenarios) + STARTUP_ALLOWANCE_SECONDS


STARTUP_ALLOWANCE_SECONDS = 30
"""Time a pod may spend starting (image, volumes, interpreter) before its scenario clock runs;
the runner enforces ``timeout_seconds`` itself, the deadline is the backstop."""
