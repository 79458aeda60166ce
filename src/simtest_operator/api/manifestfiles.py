"""Reading manifest files: bounded size, depth and alias expansion, one-line errors.

``simtest run``, ``simtest render`` and ``simtest submit`` read manifests only through
:func:`read`, so a hostile file gets the same answer everywhere: a :class:`ScenarioError` naming
the problem on one line (exit 2), never a traceback (issue 12: non-UTF-8 bytes, 100k-deep
nesting and a 50 MB include list crashed or stalled the CLI).

Limits, chosen from what the cluster would accept anyway:

* :data:`MAX_BYTES` -- etcd's default request limit (``--max-request-bytes``, 1.5 MiB) caps every
  object the API server stores, so a larger manifest could never be applied;
* :data:`MAX_DEPTH` -- the deepest manifest of ours nests about 10 levels; Python's own recursion
  (PyYAML's constructor, pydantic) gives out near 1000, so 100 leaves room for free-form values;
* :data:`MAX_NODES` -- nodes after expanding aliases: ``&a [*b, *b, ...]`` chains ("billion
  laughs") are small as text but huge once a consumer (JSON, the API server) expands them.

Depth and expansion are counted on libyaml's event stream, which needs no recursion, before the
document is built with libyaml's C safe loader.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from simtest_operator.errors import ScenarioError

MAX_BYTES = 1536 * 1024
"""Largest manifest file read (etcd's default object limit)."""
MAX_DEPTH = 100
"""Deepest nesting of mappings and sequences."""
MAX_NODES = 1_000_000
"""Most nodes in the documents with every alias expanded."""

_LOADER: type[yaml.SafeLoader] = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def read(path: Path) -> tuple[str, list[Any]]:
    """The manifest's text and its non-empty documents; ScenarioError (one line) otherwise."""
    try:
        with path.open("rb") as stream:
            raw = stream.read(MAX_BYTES + 1)
    except OSError as exc:
        raise ScenarioError(f"cannot read manifest: {exc.strerror or exc}", file=str(path)) from exc
    if len(raw) > MAX_BYTES:
        raise ScenarioError(
            f"manifest is larger than {MAX_BYTES // 1024} KiB, the most the API server stores; "
            "select scenarios with patterns or labels instead of long lists",
            file=str(path),
        )
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise ScenarioError(
            f"manifest is not UTF-8 text: byte 0x{raw[exc.start]:02x} at line {line}",
            file=str(path),
        ) from None
    try:
        _check_shape(text)
        documents = [d for d in yaml.load_all(text, Loader=_LOADER) if d is not None]
    except yaml.YAMLError as exc:
        raise ScenarioError(
            f"manifest is not valid YAML: {_one_line(exc)}", file=str(path)
        ) from None
    except _LimitError as exc:
        raise ScenarioError(f"manifest {exc}", file=str(path)) from None
    return text, documents


class _LimitError(Exception):
    """The event stream went past a limit (the message says which)."""


def _check_shape(text: str) -> None:
    seen = 0
    """Nodes so far, every alias counted as the size of what it names."""
    open_collections: list[tuple[str | None, int]] = []
    """(anchor, ``seen`` at its start) of each collection being read."""
    sizes: dict[str, int] = {}
    for event in yaml.parse(text, Loader=_LOADER):
        if isinstance(event, yaml.CollectionStartEvent):
            if len(open_collections) >= MAX_DEPTH:
                raise _LimitError(f"nests deeper than {MAX_DEPTH} levels")
            open_collections.append((event.anchor, seen))
            seen += 1
        elif isinstance(event, yaml.CollectionEndEvent):
            anchor, at = open_collections.pop()
            if anchor is not None:
                sizes[anchor] = seen - at
        elif isinstance(event, yaml.ScalarEvent):
            seen += 1
            if event.anchor is not None:
                sizes[event.anchor] = 1
        elif isinstance(event, yaml.AliasEvent):
            seen += sizes.get(str(event.anchor), 1)
        if seen > MAX_NODES:
            raise _LimitError(f"has more than {MAX_NODES} values once its aliases are expanded")


def _one_line(exc: yaml.YAMLError) -> str:
    if not isinstance(exc, yaml.MarkedYAMLError):
        return " ".join(str(exc).split())
    mark = exc.problem_mark or exc.context_mark
    where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
    context = f" ({exc.context})" if exc.context else ""
    return f"{where}{exc.problem or 'invalid YAML'}{context}"
