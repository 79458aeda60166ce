"""Running scenarios on this machine: one scenario (simulation, evaluation, recording), a whole
campaign over worker processes, re-scoring recorded runs, and the simulator pod's entrypoint.

This module is the package's public entry, and the only part of it the CLI may import
(import-linter enforces that): one scenario (:func:`run_scenario`, :func:`run_many` over
:class:`RunRequest` -> :class:`RunReport`), a campaign (:func:`run_campaign` over a
:class:`LocalRunRequest`, its events :class:`Prepared`, :class:`Retrying`, :class:`Finished` and
its :class:`LocalRunResult`; :func:`engine` picks what runs each scenario), the frozen list
(:func:`read_manifest`, :func:`freeze`), exit codes (:func:`summarise`, :data:`EXIT_ERROR`),
re-scoring (:func:`reevaluate`) and reading a recording (:func:`read_recording`). The pod's
entrypoint is the ``simtest-runner`` console script (:mod:`.launch`, which runs
:mod:`.entrypoint`).

Names load on first use (PEP 562 ``__getattr__``): each caller pays only for the module behind
the names it touches, so ``simtest scenario run`` starts without the campaign machinery (pydantic,
YAML, Jinja) and ``simtest report`` without the simulator (numpy).
"""

from __future__ import annotations

import importlib
from collections.abc import Sequence
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:
    from simtest_operator.results.records import CampaignRecord, StoredOutcome
    from simtest_operator.results.reportmodel import SearchSection
    from simtest_operator.runner.campaigns import Event as CampaignEvent
    from simtest_operator.runner.campaigns import LocalRunResult, Prepared, read_recording
    from simtest_operator.runner.campaigns import run as run_campaign
    from simtest_operator.runner.preparing import LocalRunRequest, read_manifest
    from simtest_operator.runner.reevaluation import EvaluateRequest, reevaluate
    from simtest_operator.runner.resolving import freeze
    from simtest_operator.runner.scenario_execution import (
        RunReport,
        RunRequest,
        run_many,
        run_scenario,
    )
    from simtest_operator.runner.scheduling import Finished, Retrying
    from simtest_operator.runner.searchresults import export as export_search
    from simtest_operator.runner.searchresults import lines as search_lines
    from simtest_operator.runner.searchresults import recorded as recorded_search
    from simtest_operator.runner.searchresults import section as search_section
    from simtest_operator.runner.summaries import EXIT_ERROR, summarise
    from simtest_operator.runner.tasks import ExecuteFn

__all__ = [
    "EXIT_ERROR",
    "CampaignEvent",
    "EvaluateRequest",
    "Finished",
    "LocalRunRequest",
    "LocalRunResult",
    "Prepared",
    "Retrying",
    "RunReport",
    "RunRequest",
    "engine",
    "export_search",
    "freeze",
    "read_manifest",
    "read_recording",
    "recorded_search",
    "reevaluate",
    "run_campaign",
    "run_many",
    "run_scenario",
    "search_lines",
    "search_section",
    "search_section_of",
    "summarise",
]

_HOMES = {
    "CampaignEvent": ("campaigns", "Event"),
    "LocalRunResult": ("campaigns", "LocalRunResult"),
    "Prepared": ("campaigns", "Prepared"),
    "read_recording": ("campaigns", "read_recording"),
    "run_campaign": ("campaigns", "run"),
    "LocalRunRequest": ("preparing", "LocalRunRequest"),
    "read_manifest": ("preparing", "read_manifest"),
    "EvaluateRequest": ("reevaluation", "EvaluateRequest"),
    "reevaluate": ("reevaluation", "reevaluate"),
    "freeze": ("resolving", "freeze"),
    "RunReport": ("scenario_execution", "RunReport"),
    "RunRequest": ("scenario_execution", "RunRequest"),
    "run_many": ("scenario_execution", "run_many"),
    "run_scenario": ("scenario_execution", "run_scenario"),
    "Finished": ("scheduling", "Finished"),
    "export_search": ("searchresults", "export"),
    "search_lines": ("searchresults", "lines"),
    "recorded_search": ("searchresults", "recorded"),
    "search_section": ("searchresults", "section"),
    "Retrying": ("scheduling", "Retrying"),
    "EXIT_ERROR": ("summaries", "EXIT_ERROR"),
    "summarise": ("summaries", "summarise"),
}
"""Public name -> (module of this package, attribute) it is loaded from on first use."""


def __getattr__(name: str) -> object:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module, attribute = home
    value = getattr(importlib.import_module(f"{__name__}.{module}"), attribute)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})


def engine(name: Literal["sumo", "fake"]) -> ExecuteFn:
    """What runs each scenario of a local campaign: the simulator, or the documented test double
    (:mod:`.fakes`, for tests only)."""
    if name == "fake":
        from simtest_operator.runner import fakes

        return fakes.execute
    from simtest_operator.runner import engines

    return engines.execute


def search_section_of(
    campaign: CampaignRecord, stored: Sequence[StoredOutcome]
) -> SearchSection | None:
    """The *Search* section of a stored run for the report and the results UI; the search
    engine (scikit-learn, matplotlib) is imported only for a run that searched."""
    if "search" not in campaign.info.settings:
        return None
    from simtest_operator.runner import searchresults

    return searchresults.section_of(campaign, stored)
