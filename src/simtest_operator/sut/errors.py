"""Failures of an external SUT: the SUT is at fault, so the run ends ``Error`` (and is retried),
never ``Failed`` or ``Invalid``."""

from __future__ import annotations

from simtest_operator.errors import SimtestError


class SutError(SimtestError):
    """The external SUT did not start, crashed, missed its deadline or broke the protocol."""


class SutProtocolError(SutError):
    """A frame or OSI message from the SUT is malformed."""


class SutDeadlineError(SutError):
    """The SUT did not answer a step within the per-step deadline."""
