"""Names and ids a template derives from an environment's identity — never random.

Helm release names are limited to 53 characters and parallel ROS 2 stacks must not discover each
other, so templates get both from here: a release name that stays unique when it has to be
shortened, and a ROS_DOMAIN_ID spread over the ids DDS can use on Linux without port clashes.
"""

from __future__ import annotations

import hashlib

MAX_RELEASE = 53
"""Helm's limit for a release name (it becomes part of Secret/ConfigMap names and labels)."""
RELEASE_LENGTH = 52
"""Length :func:`release_name` stays within: K8s-ROS cuts resource-name prefixes at 52, so a
release name that long is also the full name of its objects (DNS names of DDS peers)."""
DOMAIN_IDS = 101
"""ROS_DOMAIN_ID 1..101: 0 is the domain every unconfigured node joins, and ids above 101 collide
with Linux's ephemeral port range (DDS ports are 7400 + 250 * id + offset)."""
ENVIRONMENT_LABEL = "simtest.dev/environment"
"""Label naming the SimEnvironment on every object of its stack (other than its pod)."""


def _digest(text: str, n: int) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:n]


def release_name(environment: str, component: str) -> str:
    """``<environment>-<component>``; past 52 characters the environment part is cut and an
    8-digit digest of the full name keeps it unique."""
    name = f"{environment}-{component}"
    if len(name) <= RELEASE_LENGTH:
        return name
    keep = RELEASE_LENGTH - len(component) - 10  # "-" + digest + "-"
    if keep < 1:
        raise ValueError(f"component name {component!r} is too long for a Helm release name")
    head = environment[:keep].rstrip("-.")
    return f"{head}-{_digest(name, 8)}-{component}"


def ros_domain_id(namespace: str, environment: str) -> int:
    """A ROS_DOMAIN_ID in 1..101 derived from the environment; two environments may share one
    (there are only 101), which is why templates also restrict DDS discovery to their own peers."""
    return 1 + int(_digest(f"{namespace}/{environment}", 8), 16) % DOMAIN_IDS
