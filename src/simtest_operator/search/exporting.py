"""Concrete ``.xosc`` files of chosen proposals, for a regression suite."""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

from simtest_operator.openscenario import concretising
from simtest_operator.openscenario.confinement import Confinement
from simtest_operator.search.records import Proposal

_UNSAFE = re.compile(r"[^A-Za-z0-9._+-]+")
MAX_NAME = 180
"""File names stay well below the 255 bytes file systems allow."""


def export_scenarios(
    scenario_path: Path,
    proposals: Sequence[Proposal],
    out_dir: Path,
    *,
    source_root: Path | None = None,
) -> list[Path]:
    """Write one concrete scenario per proposal into ``out_dir`` (created when missing), with
    copies of the road network and catalogs it references (from within ``source_root``, else
    the scenario's git work tree), so the folder runs on its own.

    The file is the logical scenario with its ParameterDeclarations' values replaced; its name
    carries the stem, the proposal index and the values, e.g.
    ``cut-in_search-12_EgoSpeed-31.5_CutInGap-8.xosc``.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    confinement = Confinement.for_scenario(scenario_path, source_root)
    references = concretising.bundle(scenario_path, out_dir, confinement=confinement)
    written = []
    for proposal in proposals:
        overrides = proposal.overrides()
        values = "_".join(f"{name}-{text}" for name, text in overrides.items())
        stem = _UNSAFE.sub("-", f"{scenario_path.stem}_search-{proposal.index}_{values}")
        stem = stem[:MAX_NAME]
        target = out_dir / f"{stem}.xosc"
        target.write_bytes(concretising.concretise(scenario_path, overrides, references=references))
        written.append(target)
    return written
