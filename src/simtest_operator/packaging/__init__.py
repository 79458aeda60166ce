"""Packaging: the charts' generated artefacts, ROS 2 application charts from a small spec
(K8s-ROS), and the Job that applies a rendered helmfile (``provisioner: Helmfile``).

Pure like ``render`` (its neighbour in the layer map, which it does not import): specs and
requests in, file contents and manifests out; only ``load_inputs``/``write``/``sync`` touch disk.
"""

from simtest_operator.packaging.helmfilejobs import (
    IMAGE_CHARTS_DIR,
    Action,
    HelmfileJobRequest,
    Owner,
)
from simtest_operator.packaging.rosspecs import RosPackageSpec

__all__ = [
    "IMAGE_CHARTS_DIR",
    "Action",
    "HelmfileJobRequest",
    "Owner",
    "RosPackageSpec",
]
