"""The images ``deploy/docker/build.sh`` built, as a real node gets them.

The build script keeps an index, ``<cache>/images/images.json``, of every image it built: name,
OCI archive, digest, size. A real node imports those archives instead of pulling from a registry
(none is reachable here), so pods name the images exactly as on a real cluster
(``ghcr.io/simtest-dev/simtest-runner:0.1.0``) and the kubelet finds them present.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from simtest_operator.devcluster import addons
from simtest_operator.devcluster.realnodes import RealNodeSetup
from simtest_operator.errors import ClusterError
from simtest_operator.settings import CacheSettings

BUILD_SCRIPT = Path("deploy/docker/build.sh")
RUNNER_IMAGE = "ghcr.io/simtest-dev/simtest-runner:0.1.0"
DEVICE_PLUGIN_IMAGE = "ghcr.io/simtest-dev/simtest-device-plugin:0.1.0"
SUT_GO_IMAGE = "ghcr.io/simtest-dev/simtest-sut-go:0.1.0"
"""The example system under test in Go (``deploy/sut-go``), run as a sidecar."""
SANDBOX_PREFIX = "localhost/simtest/pause:"
"""Name prefix of the pod-sandbox image the build script makes (a static ``pause``)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class BuiltImage:
    name: str
    archive: Path
    digest: str
    size: int


def index_path(cache_root: Path) -> Path:
    return CacheSettings(root=cache_root).image_index


def load_index(path: Path) -> dict[str, BuiltImage]:
    """Every image in the build script's index, by name; a clear error when there is none."""
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise ClusterError(
            f"no images built yet ({path} is missing); run `bash {BUILD_SCRIPT}` "
            "from the repository root"
        ) from None
    except ValueError as exc:
        raise ClusterError(f"unreadable image index {path}: {exc}") from exc
    entries = data.get("images", data) if isinstance(data, dict) else {}
    images = {}
    for name, entry in entries.items():
        archive = Path(entry["archive"])
        if not archive.is_file():
            raise ClusterError(f"{path} names {archive} for {name}, but it is gone; rebuild")
        images[name] = BuiltImage(
            name=name,
            archive=archive,
            digest=str(entry.get("digest", "")),
            size=int(entry.get("size", 0)),
        )
    return images


def real_node_setup(
    cache_root: Path, *, helm: Path, chart: Path, slots: int, wanted: tuple[str, ...] = ()
) -> RealNodeSetup:
    """What the real node gets: the sandbox image plus ``wanted`` (default: every built image)
    from the build script's index, and the chart's device plugin advertising ``slots``."""
    index = load_index(index_path(cache_root))
    sandboxes = sorted(name for name in index if name.startswith(SANDBOX_PREFIX))
    if not sandboxes:
        raise ClusterError(f"the image index has no pod sandbox image ({SANDBOX_PREFIX}*)")
    names = wanted or tuple(index)
    unknown = sorted(set(names) - set(index))
    if unknown:
        raise ClusterError(f"not built: {', '.join(unknown)}; run `bash {BUILD_SCRIPT}`")
    chosen = dict.fromkeys((sandboxes[-1], *names))
    plugin = addons.device_plugin_documents(helm, chart, image=DEVICE_PLUGIN_IMAGE, slots=slots)
    return RealNodeSetup(
        sandbox_image=sandboxes[-1],
        archives=tuple(index[n].archive for n in chosen),
        addons=tuple(plugin),
    )
