"""Search for failures: propose concrete scenarios of a logical one where the system may break.

The package is the engine only: a :class:`Searcher` asks a strategy for proposals and is told
outcomes; the operator and ``simtest run`` run the proposals as normal scenarios. The summary
(failures, failure regions, the estimated boundary, the most critical runs), the plots and the
export of concrete ``.xosc`` files work on the recorded proposals and outcomes.
"""

from simtest_operator.search.analysis import SearchSummary, fit_boundary, summarise
from simtest_operator.search.exporting import export_scenarios
from simtest_operator.search.plotting import plot_pairs
from simtest_operator.search.records import Outcome, Proposal, criticality
from simtest_operator.search.searching import ReplayError, Searcher
from simtest_operator.search.spaces import Dimension, SearchSpace

__all__ = [
    "Dimension",
    "Outcome",
    "Proposal",
    "ReplayError",
    "SearchSpace",
    "SearchSummary",
    "Searcher",
    "criticality",
    "export_scenarios",
    "fit_boundary",
    "plot_pairs",
    "summarise",
]
