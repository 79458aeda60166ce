"""Pure rendering of environment templates (``helm-templates/``) into Helm values, the simulator
pod and a run-specific helmfile; plus the run-spec contract between pod and runner.

Names load on first use (PEP 562 ``__getattr__``): the simulator pod reads its run spec and
writes its termination message through :mod:`.runspecs` and :mod:`.messages` and renders
nothing, so it does not import the renderer's Jinja and YAML.
"""

from typing import TYPE_CHECKING

from simtest_operator import lazyimports

if TYPE_CHECKING:
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

_MODULES = {
    "CHARTS_DIR": "inputs",
    "SIMULATOR_RESOURCE": "inputs",
    "Amounts": "inputs",
    "ArtifactTarget": "inputs",
    "EnvironmentRequest": "inputs",
    "OwnerRef": "inputs",
    "PvcVolume": "inputs",
    "S3Target": "inputs",
    "ScenarioRef": "inputs",
    "SecretKey": "inputs",
    "RenderedEnvironment": "rendering",
    "render_environment": "rendering",
    "RunSpec": "runspecs",
    "TemplateLibrary": "templates",
}


__getattr__ = lazyimports.loader(__name__, _MODULES)


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
