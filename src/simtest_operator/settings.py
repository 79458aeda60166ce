"""Settings: one root object of small topic groups, built once at the edge and passed down.

Only :func:`Settings.from_env` reads the environment (prefix ``SIMTEST_``); inner packages receive
the object as an argument and never look at ``os.environ`` themselves.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping
from pathlib import Path

ENV_PREFIX = "SIMTEST_"


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
class Settings:
    """The root settings object."""

    cache: CacheSettings
    simulation: SimulationSettings = dataclasses.field(default_factory=SimulationSettings)
    maps: tuple[Path, ...] = ()
    """User map libraries (``SIMTEST_MAP_PATH``, folders separated by ``:``): folders of
    ``<name>.xodr`` a scenario names with ``<LogicFile filepath="<name>"/>``, searched before
    the CARLA towns shipped with the product."""

    @classmethod
    def from_env(cls, env: Mapping[str, str] | None = None) -> Settings:
        """Build settings from ``SIMTEST_*`` variables (defaults for the rest)."""
        env = os.environ if env is None else env
        cache_root = env.get(f"{ENV_PREFIX}CACHE_DIR")
        defaults = SimulationSettings()
        simulation = SimulationSettings(
            step_length=float(env.get(f"{ENV_PREFIX}STEP_LENGTH", defaults.step_length)),
            seed=int(env.get(f"{ENV_PREFIX}SEED", defaults.seed)),
        )
        return cls(
            cache=CacheSettings(
                root=Path(cache_root) if cache_root else _default_cache_dir(env),
            ),
            simulation=simulation,
            maps=tuple(
                Path(p) for p in env.get(f"{ENV_PREFIX}MAP_PATH", "").split(os.pathsep) if p
            ),
        )
