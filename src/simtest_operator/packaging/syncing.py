"""Generated chart artefacts, kept in step with their one source (STYLE rule 19).

- ``crds/`` is generated from the API models (``simtest crds``); a Helm chart can only read files
  inside its own folder, so the operator chart carries byte-identical copies.
- The values tables in docs/install.md and docs/ros-packaging.md are generated from the charts'
  ``# --`` comments (:mod:`valuesdoc`).

``sync_all`` writes them (or, with ``check``, only reports drift), like ``crdgen.sync`` does for
``crds/``; ``simtest package sync [--check]`` is the command, and a test runs the check.
"""

from __future__ import annotations

from pathlib import Path

from simtest_operator.packaging import valuesdoc

CRDS_DIR = Path("crds")
"""The generated CRDs, relative to the repository root."""
CHART_CRDS_DIR = Path("charts/simtest-operator/files/crds")
"""Their copies inside the operator chart, relative to the repository root."""
VALUES_DOCS = (
    (Path("charts/simtest-operator/values.yaml"), Path("docs/install.md")),
    (Path("charts/k8s-ros/values.yaml"), Path("docs/ros-packaging.md")),
)
"""(values file, document embedding its table), relative to the repository root."""


def sync_all(root: Path, *, check: bool = False) -> list[Path]:
    """Every generated chart artefact under ``root``; returns the paths that differ."""
    drift = [
        root / CHART_CRDS_DIR / name
        for name in sync(root / CRDS_DIR, root / CHART_CRDS_DIR, check=check)
    ]
    for values_path, doc_path in VALUES_DOCS:
        rows = valuesdoc.documented((root / values_path).read_text(encoding="utf-8"))
        current = (root / doc_path).read_text(encoding="utf-8")
        wanted = valuesdoc.embed(current, rows)
        if wanted != current:
            drift.append(root / doc_path)
            if not check:
                (root / doc_path).write_text(wanted, encoding="utf-8")
    return drift


def sync(source: Path, target: Path, *, check: bool = False) -> list[str]:
    """Make ``target`` hold exactly the ``*.yaml`` files of ``source``; returns the file names that
    differ (changed, missing or extra). With ``check`` nothing is written."""
    wanted = {path.name: path.read_bytes() for path in sorted(source.glob("*.yaml"))}
    present = {path.name: path.read_bytes() for path in sorted(target.glob("*.yaml"))}
    drift = sorted(
        name for name in wanted.keys() | present.keys() if wanted.get(name) != present.get(name)
    )
    if check or not drift:
        return drift
    target.mkdir(parents=True, exist_ok=True)
    for name in drift:
        if name in wanted:
            (target / name).write_bytes(wanted[name])
        else:
            (target / name).unlink()
    return drift
