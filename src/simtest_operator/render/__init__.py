"""Pure rendering of environment templates (``helm-templates/``) into Helm values, the simulator
pod and a run-specific helmfile; plus the run-spec contract between pod and runner."""

from simtest_operator.render.inputs import (
    CHARTS_DIR,
    SIMULATOR_RESOURCE,
    Amounts,
    ArtifactTarget,
    EnvironmentRequest,
    OwnerRef,
    PvcVolume,
    S3Target,
    ScenarioRef,
    SecretKey,
)
from simtest_operator.render.rendering import RenderedEnvironment, render_environment
from simtest_operator.render.runspecs import RunSpec
from simtest_operator.render.templates import TemplateLibrary

__all__ = [
    "CHARTS_DIR",
    "SIMULATOR_RESOURCE",
    "Amounts",
    "ArtifactTarget",
    "EnvironmentRequest",
    "OwnerRef",
    "PvcVolume",
    "RenderedEnvironment",
    "RunSpec",
    "S3Target",
    "ScenarioRef",
    "SecretKey",
    "TemplateLibrary",
    "render_environment",
]
