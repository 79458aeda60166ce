"""Settings: one root object of small topic groups, built once at the edge and passed down.

The shape is kopf's ``OperatorSettings``: a root (:class:`Settings`) of frozen topic dataclasses,
each field documented with its default and why. Only :meth:`Settings.from_env` reads the
environment (``SIMTEST_*``, and ``SIMTEST_OPERATOR_*`` for the operator's topic), once per entry
point: ``simtest`` commands, ``simtest operator`` and the runner pod's entrypoint. Inner packages
receive the object (or one topic of it) as an argument and never look at ``os.environ``.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Mapping
from pathlib import Path

ENV_PREFIX = "SIMTEST_"
OPERATOR_PREFIX = "SIMTEST_OPERATOR_"
"""Prefix of the operator's installation knobs (the chart sets them; flags override them)."""
SECRET_PREFIX = f"{ENV_PREFIX}SECRET_"
"""Prefix of the variables that stand in for Secret keys in local runs."""
SOURCE_TOKEN_PREFIX = f"{ENV_PREFIX}SOURCE_TOKEN_"
"""Prefix of the variables a simulator pod's template maps Secret keys into (numbered, from the
run spec: :func:`simtest_operator.render.runspecs.secret_variables`)."""
RESULTS_DSN = f"{ENV_PREFIX}RESULTS_DSN"
"""The variable a simulator pod's or an evaluation Job's template fills from the DSN Secret."""
RESULTS_RUN_KEY = f"{ENV_PREFIX}RESULTS_RUN_KEY"
"""The variable carrying the run key a simulator pod's rows are stored under."""
SUT_ENDPOINT = f"{ENV_PREFIX}SUT_ENDPOINT"
"""The variable a simulator pod's template sets to where its external SUT listens: the sidecar
on loopback, or the Service of a composed SUT stack (template ``composed-sut``)."""
SUT_OUTPUT_DIR = f"{ENV_PREFIX}SUT_OUTPUT_DIR"
"""The variable a simulator pod's template sets to the folder its sidecars print into (one
``<container>.log`` each): the runner keeps what they printed during a scenario as its
``sut.log``."""


def _default_cache_dir(env: Mapping[str, str]) -> Path:
    base = env.get("XDG_CACHE_HOME") or str(Path(env.get("HOME", "/tmp")) / ".cache")
    return Path(base) / "simtest"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class CacheSettings:
    """Where derived, re-creatable files live (outside the repository)."""

    root: Path
    """Cache root, default ``$XDG_CACHE_HOME/simtest`` or ``~/.cache/simtest``
    (``SIMTEST_CACHE_DIR``). Holds built binaries, converted SUMO nets and Go caches."""

    @property
    def nets(self) -> Path:
        """Converted SUMO networks, keyed by the content hash of their OpenDRIVE file."""
        return self.root / "nets"

    @property
    def sources(self) -> Path:
        """Fetched scenario sources (git clones, downloaded archives), keyed by what was fetched."""
        return self.root / "sources"

    @property
    def image_index(self) -> Path:
        """``images.json``, the index of the container images ``deploy/docker/build.sh`` built
        (name, OCI archive, manifest digest): what a real node imports, and how ``simtest run``
        names the digest of a SUT image."""
        return self.root / "images" / "images.json"

    @property
    def toolchain(self) -> Path:
        """Control-plane, kwok, helm and helmfile binaries plus Go module and build caches."""
        return self.root / "toolchain"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SimulationSettings:
    """Defaults for the simulator stand-in; a campaign's simulator settings override them."""

    step_length: float = 0.05
    """Simulation step in seconds (20 Hz: fine enough for TTC, twice the recording minimum)."""
    seed: int = 42
    """Seed for SUMO and every local random generator, so runs are reproducible."""
    record_hz: float = 10.0
    """Recording rate of the ground-truth MCAP; omega-prime needs at least 10 Hz."""
    real_time_factor: float = 0.0
    """Pace: simulated seconds per wall second (1.0 is real time, as a SUT with hard timing or a
    rendering simulator like CARLA runs); 0 runs as fast as possible."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class InputSettings:
    """Where the operator finds environment templates and scenario sources."""

    templates_dir: Path = Path("helm-templates")
    """Root of the environment templates (``helm-templates/``); ``SIMTEST_OPERATOR_TEMPLATES``."""
    sources_dir: Path = Path()
    """Folder relative ``path`` scenario sources are resolved against (the operator's scenario
    volume); ``SIMTEST_OPERATOR_SOURCES``."""
    cache_dir: Path = Path("/tmp/simtest-operator-cache")
    """Downloads, git mirrors and unpacked archives of resolution; ``SIMTEST_OPERATOR_CACHE``."""
    scenario_claim: str = ""
    """PVC holding ``path`` sources, mounted read-only into simulator pods at ``sources_dir``
    (``SIMTEST_OPERATOR_SCENARIO_CLAIM``); empty: none, and a pod cannot read ``file://``
    sources (its scenarios end ``Error`` with a hint to set this)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class PacingSettings:
    """How often the operator writes and how much one step does."""

    status_interval: float = 1.0
    """Minimum seconds between two campaign status writes that change counters only; phase and
    condition changes are written at once. Fewer writes, same end state."""
    event_interval: float = 10.0
    """Minimum seconds between two events on the same object (terminal phases always post)."""
    prefetch_per_node: int = 1
    """Window mode with a derived window (no maxParallel): pods created beyond the free
    simulator slots, per usable node. They wait in Pending and the scheduler starts one the
    moment a slot frees, without a round trip through the operator. 0 turns it off."""
    max_starts_per_step: int = 64
    """Environments one step may create; the rest start in the next step, right after. Keeps a
    step short when a large window opens at once (a 150-slot ramp), so results that arrive
    meanwhile are folded without waiting for hundreds of writes."""
    reuse_queue: int = 8
    """Scenarios per warm simulator with isolation ``Reuse`` (bounded by the 4 KiB termination
    message that carries their results)."""
    release_exited: bool = True
    """Delete a finished environment's pod without grace once its simulator container has
    exited, so the scheduler frees the slot at once instead of a kubelet relist (~1 s) later.
    False: the graceful delete (the measured baseline of ``bench/real_table1.py``)."""
    coalesce_seconds: float = 0.02
    """How long a campaign loop waits after a wake-up for more events to arrive."""
    api_workers: int = 16
    """Threads for Kubernetes API calls."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class GraceSettings:
    """How long the operator waits before it judges a run by what is missing."""

    missing_pod_grace: float = 10.0
    """Seconds a pod recorded as created may be missing from the cache before it counts as
    deleted."""
    backstop_grace: float = 30.0
    """Seconds past a pod's activeDeadlineSeconds before the operator ends the run as Timeout
    itself (when no kubelet enforces the deadline)."""
    node_not_ready_grace: float = 60.0
    """Seconds a simulator pod's node may be NotReady (kubelet stopped, node cut off) before its
    scenarios end Error and are retried on another node; the pod is force-deleted."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LeadershipSettings:
    """Leader election among replicas over a coordination.k8s.io Lease."""

    enabled: bool = False
    """Run campaign loops only while holding the Lease ``lease_name`` (two or more replicas);
    ``SIMTEST_OPERATOR_LEADER_ELECTION``. Off: this process always acts (one replica)."""
    lease_name: str = "simtest-operator"
    """Name of the Lease; ``SIMTEST_OPERATOR_LEASE_NAME``."""
    lease_namespace: str = ""
    """Namespace of the Lease (the operator's own); empty: the first watched namespace, else
    ``default``; ``SIMTEST_OPERATOR_LEASE_NAMESPACE``."""
    identity: str = ""
    """Holder identity in the Lease (the pod name); empty: ``<hostname>_<pid>``;
    ``SIMTEST_OPERATOR_IDENTITY``."""
    lease_duration: float = 15.0
    """Seconds without a renewal before a follower takes over (client-go's default)."""
    renew_deadline: float = 10.0
    """Seconds the leader keeps acting without a successful renewal (client-go's default)."""
    retry_period: float = 2.0
    """Seconds between two acquire/renew attempts (client-go's default)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class HelmfileSettings:
    """The Jobs of ``provisioner: Helmfile`` environments."""

    image: str = ""
    """Image of the Jobs (helm, helmfile and ``charts/``); ``SIMTEST_OPERATOR_HELMFILE_IMAGE``.
    Empty: campaigns asking for the Helmfile provisioner end their environments as Error with a
    reason saying so."""
    role: str = ""
    """ClusterRole bound (per campaign, in its namespace) to the Jobs' ServiceAccount;
    ``SIMTEST_OPERATOR_HELMFILE_ROLE`` (the chart's ``<release>-helmfile-provisioner``)."""
    node_selector: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """Node selector of the Jobs (``key=value,...``; ``SIMTEST_OPERATOR_HELMFILE_NODE_SELECTOR``):
    provisioning needs no simulator node, and may need nodes that reach chart registries."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class OperatorSettings:
    """How the operator runs: knobs of the installation, not of a campaign, by topic."""

    inputs: InputSettings = dataclasses.field(default_factory=InputSettings)
    pacing: PacingSettings = dataclasses.field(default_factory=PacingSettings)
    graces: GraceSettings = dataclasses.field(default_factory=GraceSettings)
    leadership: LeadershipSettings = dataclasses.field(default_factory=LeadershipSettings)
    helmfile: HelmfileSettings = dataclasses.field(default_factory=HelmfileSettings)
    metrics_port: int = 8080
    """Port of ``/metrics``, ``/healthz`` and ``/readyz``; 0 disables the server;
    ``SIMTEST_OPERATOR_METRICS_PORT``."""
    keep_finished_environments: bool = False
    """Keep SimEnvironments after their results are folded into the batch (debugging); by
    default they are deleted so live objects stay bounded by the in-flight window;
    ``SIMTEST_OPERATOR_KEEP_ENVIRONMENTS``."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ResultsSettings:
    """Where results are read and written when no option says so. The DSNs may hold passwords,
    so they stay out of the repr."""

    database: str | None = dataclasses.field(default=None, repr=False)
    """The results database (a PostgreSQL DSN, an output folder or a SQLite file) ``simtest
    report`` and ``simtest ui`` read when ``--database`` is not given
    (``SIMTEST_RESULTS_DATABASE``; unset or empty: none)."""
    dsn: str = dataclasses.field(default="", repr=False)
    """The results database a simulator pod writes its rows to and ``simtest evaluate`` reads
    when no source is given (``SIMTEST_RESULTS_DSN``, from a Secret so the DSN stays off the
    command line; empty: none)."""
    run_key: str = ""
    """The run a simulator pod's rows belong to (``SIMTEST_RESULTS_RUN_KEY``)."""
    summary_file: Path | None = None
    """Where ``simtest evaluate`` also writes its outcome as JSON when ``--summary-file`` is not
    given (``SIMTEST_EVALUATE_SUMMARY_FILE``)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Settings:
    """The root settings object."""

    cache: CacheSettings
    simulation: SimulationSettings = dataclasses.field(default_factory=SimulationSettings)
    maps: tuple[Path, ...] = ()
    """User map libraries (``SIMTEST_MAP_PATH``, folders separated by ``:``): folders of
    ``<name>.xodr`` a scenario names with ``<LogicFile filepath="<name>"/>``, searched before
    the CARLA towns shipped with the product."""
    operator: OperatorSettings = dataclasses.field(default_factory=OperatorSettings, hash=False)
    """The operator's knobs (``SIMTEST_OPERATOR_*``); only ``simtest operator`` uses them."""
    secrets: Mapping[str, str] = dataclasses.field(default_factory=dict, repr=False, hash=False)
    """``SIMTEST_SECRET_<NAME>_<KEY>`` variables by name: Secret values for local runs
    (``simtest run``, ``simtest render``), which have no cluster to read Secrets from. Left out
    of the repr so they never reach a log."""
    source_tokens: Mapping[str, str] = dataclasses.field(
        default_factory=dict, repr=False, hash=False
    )
    """``SIMTEST_SOURCE_TOKEN_<n>`` variables by name: the Secret keys a simulator pod's scenario
    databases need, mapped in by its template (the pod has no API access). Left out of the repr."""
    results: ResultsSettings = dataclasses.field(default_factory=ResultsSettings)
    """The results database's defaults (``SIMTEST_RESULTS_*``,
    ``SIMTEST_EVALUATE_SUMMARY_FILE``)."""
    sut_endpoint: str | None = None
    """``host:port`` of an external SUT launched as ``sidecar`` or ``endpoint``
    (``SIMTEST_SUT_ENDPOINT``; unset or empty: none): the pod's template knows where its SUT
    listens, so this wins over the campaign's ``endpoint``. Applied where run requests are built
    (the pod's runner, ``simtest run``)."""
    sut_output: Path | None = None
    """Folder of the pod's sidecar output files (``SIMTEST_SUT_OUTPUT_DIR``; unset: none, as
    outside a pod, where the runner keeps a SUT process's output itself)."""

    @classmethod
    def from_env(
        cls,
        env: Mapping[str, str] | None = None,
        *,
        operator_flags: Mapping[str, object] | None = None,
    ) -> Settings:
        """Defaults, then ``SIMTEST_*`` variables, then ``operator_flags``: the CLI's flags of
        ``simtest operator`` by field, ``topic.field`` inside a topic (``inputs.templates_dir``);
        a None value means the flag was not given."""
        env = os.environ if env is None else env
        cache_root = env.get(f"{ENV_PREFIX}CACHE_DIR")
        defaults = SimulationSettings()
        simulation = SimulationSettings(
            step_length=float(env.get(f"{ENV_PREFIX}STEP_LENGTH", defaults.step_length)),
            seed=int(env.get(f"{ENV_PREFIX}SEED", defaults.seed)),
        )
        operator = _with_flags(_operator(env), operator_flags or {})
        return cls(
            cache=CacheSettings(
                root=Path(cache_root) if cache_root else _default_cache_dir(env),
            ),
            simulation=simulation,
            maps=tuple(
                Path(p) for p in env.get(f"{ENV_PREFIX}MAP_PATH", "").split(os.pathsep) if p
            ),
            operator=operator,
            secrets=_prefixed(env, SECRET_PREFIX),
            source_tokens=_prefixed(env, SOURCE_TOKEN_PREFIX),
            results=ResultsSettings(
                database=env.get(f"{ENV_PREFIX}RESULTS_DATABASE") or None,
                dsn=env.get(RESULTS_DSN, "").strip(),
                run_key=env.get(RESULTS_RUN_KEY, "").strip(),
                summary_file=Path(summary)
                if (summary := env.get(f"{ENV_PREFIX}EVALUATE_SUMMARY_FILE"))
                else None,
            ),
            sut_endpoint=env.get(SUT_ENDPOINT, "").strip() or None,
            sut_output=Path(output) if (output := env.get(SUT_OUTPUT_DIR, "").strip()) else None,
        )


def _prefixed(env: Mapping[str, str], prefix: str) -> dict[str, str]:
    return {k: v for k, v in env.items() if k.startswith(prefix)}


_VARIABLES: tuple[tuple[str, str, Callable[[str], object]], ...] = (
    ("inputs.templates_dir", "TEMPLATES", Path),
    ("inputs.sources_dir", "SOURCES", Path),
    ("inputs.cache_dir", "CACHE", Path),
    ("inputs.scenario_claim", "SCENARIO_CLAIM", str),
    ("pacing.status_interval", "STATUS_INTERVAL", float),
    ("pacing.event_interval", "EVENT_INTERVAL", float),
    ("pacing.reuse_queue", "REUSE_QUEUE", int),
    ("pacing.max_starts_per_step", "MAX_STARTS_PER_STEP", int),
    ("pacing.prefetch_per_node", "PREFETCH", int),
    ("pacing.release_exited", "RELEASE_EXITED", lambda raw: raw.lower() in ("1", "true", "yes")),
    ("graces.missing_pod_grace", "MISSING_POD_GRACE", float),
    ("graces.backstop_grace", "BACKSTOP_GRACE", float),
    ("graces.node_not_ready_grace", "NODE_NOT_READY_GRACE", float),
    ("metrics_port", "METRICS_PORT", int),
    ("leadership.enabled", "LEADER_ELECTION", lambda raw: raw.lower() in ("1", "true", "yes")),
    ("leadership.lease_name", "LEASE_NAME", str),
    ("leadership.lease_namespace", "LEASE_NAMESPACE", str),
    ("leadership.identity", "IDENTITY", str),
    ("leadership.lease_duration", "LEASE_DURATION", float),
    ("leadership.renew_deadline", "RENEW_DEADLINE", float),
    ("leadership.retry_period", "RETRY_PERIOD", float),
    ("helmfile.image", "HELMFILE_IMAGE", str),
    ("helmfile.role", "HELMFILE_ROLE", str),
    ("helmfile.node_selector", "HELMFILE_NODE_SELECTOR", lambda raw: _pairs(raw)),
    (
        "keep_finished_environments",
        "KEEP_ENVIRONMENTS",
        lambda raw: raw.lower() in ("1", "true", "yes"),
    ),
)
"""Operator field (``topic.field``), variable after ``SIMTEST_OPERATOR_``, and how to read it.
An unset or empty variable keeps the default (blank for the node selector)."""


def _operator(env: Mapping[str, str]) -> OperatorSettings:
    """The operator's topics from ``SIMTEST_OPERATOR_*``."""
    values: dict[str, object] = {}
    for field, key, kind in _VARIABLES:
        raw = env.get(OPERATOR_PREFIX + key, "")
        if raw.strip() if field == "helmfile.node_selector" else raw:
            values[field] = kind(raw)
    return _with_flags(OperatorSettings(), values)


def _with_flags(operator: OperatorSettings, values: Mapping[str, object]) -> OperatorSettings:
    """``operator`` with ``values`` (``field`` or ``topic.field``; None: left as it is)."""
    top: dict[str, object] = {}
    topics: dict[str, dict[str, object]] = {}
    for name, value in values.items():
        if value is None:
            continue
        topic, _, field = name.rpartition(".")
        if topic:
            topics.setdefault(topic, {})[field] = value
        else:
            top[name] = value
    for topic, fields in topics.items():
        top[topic] = dataclasses.replace(getattr(operator, topic), **fields)
    return dataclasses.replace(operator, **top) if top else operator  # type: ignore[arg-type]


def _pairs(text: str) -> dict[str, str]:
    """``a=b,c=d`` as a mapping (blank items ignored)."""
    pairs = {}
    for item in text.split(","):
        if not item.strip():
            continue
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"{OPERATOR_PREFIX}HELMFILE_NODE_SELECTOR: {item!r} is not key=value")
        pairs[key.strip()] = value.strip()
    return pairs
