"""The one exception tree of simtest-operator.

Every failure the project raises on purpose derives from :class:`SimtestError`, so callers can catch
the whole family with one ``except``. Families say *who* is at fault, which decides what happens
next: bad input (``ScenarioError``) becomes an ``Invalid`` verdict and is never retried, while
infrastructure trouble (``SimulationError``, ``ClusterError``) becomes ``Error`` and may be retried.
"""

from __future__ import annotations

import re

_BREAK = "[\r\n\v\f\x1c-\x1e\x85\u2028\u2029]"
_LINE_BREAKS = re.compile(rf"\s*{_BREAK}+\s*")
_ONE_BREAK = re.compile(_BREAK)


class SimtestError(Exception):
    """Root of every error simtest-operator raises on purpose."""


class ScenarioError(SimtestError):
    """A scenario, manifest or source is unusable as written; fix the input, do not retry.

    The message is one line, whatever it quotes (libxml2 ends its messages with a newline): it
    becomes a verdict's reason and the CLI's one-line error (found by fuzzing, issue 29).
    """

    def __init__(
        self,
        message: str,
        *,
        file: str | None = None,
        element: str | None = None,
        line: int | None = None,
    ) -> None:
        self.file = file
        self.element = element
        self.line = line
        where = ", ".join(
            part
            for part in (
                _ONE_BREAK.sub(lambda match: f"\\x{ord(match.group()):02x}", file or ""),
                f"<{element}>" if element else None,
                f"line {line}" if line is not None else None,
            )
            if part
        )
        message = _LINE_BREAKS.sub(" ", message).strip()
        super().__init__(f"{message} ({where})" if where else message)


class UnsupportedFeatureError(ScenarioError):
    """The scenario uses an OpenSCENARIO element the stand-in does not implement."""


class SourceError(ScenarioError):
    """A scenario source (path, git, http, graphql, ConfigMap) cannot be read or is unsafe."""


class SimulationError(SimtestError):
    """The simulator backend failed (crash, bad map conversion); an infrastructure error."""


class EvaluationError(SimtestError):
    """A criterion or metric cannot be computed from what the run produced."""


class RenderError(SimtestError):
    """An environment template cannot be rendered with the given values."""


class ResultsError(SimtestError):
    """The results store or a report cannot be written or read."""


class ClusterError(SimtestError):
    """The Kubernetes API or the dev control plane misbehaved; usually transient."""


class ToolchainError(ClusterError):
    """A build tool (Go, the module proxy) or a built binary is missing or broken."""
