"""What ran: the versions every result and recording carries, for reproducibility.

The record names the simulator (SUMO and netconvert come from the ``eclipse-sumo`` wheel, the
TraCI binding from ``libsumo``), the Python runtime, and the environment the run was installed
from: the digest of the lock file (``uv.lock``) and of the installed distributions. The two
digests answer different questions: the lock says which pinned set was *meant* (the same digest
on a laptop, in CI and in the images), the installed set what actually *ran* (it would differ if
someone installed without the lock).

Read through ``importlib.metadata`` only: nothing here imports SUMO or any other heavy package.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import json
import platform
import re
import sys
from collections.abc import Iterable, Mapping
from pathlib import Path

from simtest_operator import __version__

LOCK_FILE_NAME = "uv.lock"


def lock_file(prefix: Path | None = None) -> Path | None:
    """The lock this environment was installed from, if it sits beside the environment.

    Both ways the project is installed put it there: ``make`` syncs ``.venv`` in the checkout
    next to ``uv.lock``, and the images sync ``/opt/simtest/venv`` with ``/opt/simtest/uv.lock``.
    """
    candidate = (prefix or Path(sys.prefix)).parent / LOCK_FILE_NAME
    return candidate if candidate.is_file() else None


def _sha256(data: bytes) -> str:
    return "sha256:" + hashlib.sha256(data).hexdigest()


def installed_digest(paths: Iterable[str] | None = None) -> str:
    """Digest of the installed distributions (``name==version`` lines, sorted).

    Read from the ``<name>-<version>.dist-info`` folder names on ``sys.path`` (what installers
    write, normalised per the wheel spec), not from each METADATA file: listing a few folders
    costs about a millisecond, parsing ~150 metadata files about 0.1 s of every runner's start.
    """
    found = set()
    for entry in sys.path if paths is None else paths:
        folder = Path(entry or ".")
        if not folder.is_dir():
            continue
        for info in folder.glob("*.dist-info"):
            name, _, version = info.name.removesuffix(".dist-info").partition("-")
            if version:
                found.add(f"{_normalized(name)}=={version}")
    return _sha256("\n".join(sorted(found)).encode())


def _normalized(name: str) -> str:
    """A distribution name as PEP 503 compares them (``Zope_Interface`` = ``zope-interface``)."""
    return re.sub(r"[-_.]+", "-", name).lower()


def _version_of(distribution: str) -> str:
    try:
        return importlib.metadata.version(distribution)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


@functools.cache
def versions() -> Mapping[str, str]:
    """The reproducibility record of this process (computed once; the facts cannot change)."""
    lock = lock_file()
    sumo = _version_of("eclipse-sumo")
    return {
        "simtest": __version__,
        "simulator": f"SUMO {sumo} (simtest engine {__version__})",
        "sumo": sumo,
        "netconvert": sumo,
        "libsumo": _version_of("libsumo"),
        "python": platform.python_version(),
        "lock": _sha256(lock.read_bytes()) if lock else "unknown (no uv.lock beside the env)",
        "installed": installed_digest(),
    }


# --- which container image ran -----------------------------------------------------------------

SUT_IMAGE_ID = "sut.imageID"
"""The versions entry naming the SUT image that ran: ``repo@sha256:…``, ``sha256:…`` or
:data:`UNKNOWN_IMAGE`."""
UNKNOWN_IMAGE = "unknown"
"""What a result says about an image nobody could name by digest (never a guess)."""
_RUNTIME_SCHEMES = ("docker-pullable://", "docker://", "containerd://", "cri-o://")
_DIGEST = re.compile(r"^(?:(?P<repo>[^@\s]+)@)?(?P<digest>sha256:[0-9a-f]{64})$")


def reported_image_id(image_id: str) -> str:
    """A container's ``status.*ContainerStatuses[].imageID`` as a result records it, or "".

    The kubelet reports what the runtime resolved: ``docker.io/library/x@sha256:…`` (the registry
    manifest digest, containerd and CRI-O when the image has one) or bare ``sha256:…`` (the image
    id, i.e. the config digest, for an image the runtime knows no registry digest of); cri-dockerd
    prefixes a scheme (``docker-pullable://``), which says nothing about the image and is dropped.
    Anything else (empty while the image is pulled, a malformed value) is "", not a guess.
    """
    text = image_id.strip()
    for scheme in _RUNTIME_SCHEMES:
        text = text.removeprefix(scheme)
    return text if _DIGEST.match(text) else ""


def pinned_image_id(image: str) -> str:
    """``repo@sha256:…`` of a reference pinned by digest (``repo:tag@sha256:…`` too), else ""."""
    name, at, digest = image.partition("@")
    if not at or _DIGEST.match(digest) is None:
        return ""
    return f"{_repository(name)}@{digest}"


def built_image_id(image: str, index: Path) -> str:
    """``sha256:…`` of ``image`` from the build script's index (``images.json``: the image id,
    i.e. its config digest), else "" (no index, image not built here, or an entry without one).

    The image id is what a containerd kubelet reports as the container's ``imageID`` for an
    archive it imported (``ctr images import``: no registry, no repo digest), as the real node
    shows; the archive's manifest digest names it nowhere a pod can see.
    """
    try:
        data = json.loads(index.read_text())
    except (OSError, ValueError):
        return ""
    images = data.get("images") if isinstance(data, Mapping) else None
    entry = images.get(image) if isinstance(images, Mapping) else None
    identity = str(entry.get("id", "")) if isinstance(entry, Mapping) else ""
    return identity if _DIGEST.match(identity) else ""


def _repository(name: str) -> str:
    """The reference without its tag (a ``:`` after the last ``/`` starts the tag)."""
    slash = name.rfind("/")
    colon = name.rfind(":")
    return name[:colon] if colon > slash else name
