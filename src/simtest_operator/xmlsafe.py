"""Safe parsing of untrusted XML: OpenSCENARIO scenarios and catalogs, OpenDRIVE roads.

These files come from users, git repositories and HTTP sources, so the parser must not expand
entities (billion laughs), fetch anything (external entities, DTDs over the network) or build huge
trees. Neither format needs a DOCTYPE, so any DOCTYPE or ENTITY declaration is rejected outright
rather than parsed carefully. Source line numbers stay available as ``element.sourceline``.
"""

from __future__ import annotations

import io
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Protocol

from lxml import etree

from simtest_operator.errors import ScenarioError

MAX_BYTES = 20 * 1024 * 1024
"""Default size limit (20 MB); real scenarios and catalogs are well below 1 MB, road networks
pass their own larger limit."""


class Element(Protocol):
    """The part of an lxml element the readers use (lxml ships no type stubs here)."""

    @property
    def tag(self) -> object:
        """Tag name (a str for elements)."""

    @property
    def sourceline(self) -> int | None:
        """Line of the element's start tag in its source."""

    def get(self, key: str) -> str | None:
        """Attribute value, or None."""

    def __iter__(self) -> Iterator[Element]:
        """Child nodes."""


_DECLARATION = re.compile(rb"<!\s*(DOCTYPE|ENTITY)", re.IGNORECASE)


def _parser() -> etree.XMLParser:
    # A fresh parser per call: lxml parsers keep state and are not thread-safe.
    return etree.XMLParser(
        resolve_entities=False,
        no_network=True,
        load_dtd=False,
        dtd_validation=False,
        huge_tree=False,
        remove_comments=True,
        remove_pis=True,
        collect_ids=False,
    )


def read_bytes(path: Path, *, max_bytes: int = MAX_BYTES) -> bytes:
    """Read ``path`` but refuse files larger than ``max_bytes``."""
    try:
        with path.open("rb") as handle:
            data = handle.read(max_bytes + 1)
    except OSError as exc:
        raise ScenarioError(f"cannot read file: {exc.strerror or exc}", file=str(path)) from exc
    if len(data) > max_bytes:
        raise ScenarioError(
            f"file is larger than the {max_bytes // (1024 * 1024)} MB limit", file=str(path)
        )
    return data


def parse_bytes(
    data: bytes, *, source: str, max_bytes: int = MAX_BYTES, what: str = "scenario"
) -> Element:
    """Parse ``data`` (named ``source`` in errors) and return the root element.

    Raises ScenarioError for oversize input, DOCTYPE/ENTITY declarations and malformed XML.
    """
    if len(data) > max_bytes:
        raise ScenarioError(
            f"document is larger than the {max_bytes // (1024 * 1024)} MB limit", file=source
        )
    reject_declarations(data, source, what=what)
    try:
        root = etree.fromstring(data, parser=_parser(), base_url=None)
    except etree.XMLSyntaxError as exc:
        raise ScenarioError(f"malformed XML: {exc.msg}", file=source, line=exc.lineno) from exc
    tree = root.getroottree()
    if tree.docinfo.doctype or tree.docinfo.internalDTD is not None:
        raise ScenarioError(f"DOCTYPE declarations are not allowed in {what} files", file=source)
    for node in root.iter():
        if isinstance(node, etree._Entity):
            raise ScenarioError(
                f"entity references are not allowed in {what} files",
                file=source,
                line=node.sourceline,
            )
    _strip_namespaces(root)
    result: Element = root
    return result


def stream_children(
    data: bytes, *, source: str, max_bytes: int = MAX_BYTES, what: str = "scenario"
) -> Iterator[Element]:
    """Parse ``data`` incrementally: yield the root first (attributes only, no children yet),
    then each child of the root once it is complete, freeing it when the consumer moves on.

    Peak memory is one top-level element's tree instead of the whole document's, which for large
    road networks is several times the file size (see docs/security.md for the figures). The same
    protections as :func:`parse_bytes` apply: size limit, no declarations, no entities, no network.
    """
    if len(data) > max_bytes:
        raise ScenarioError(
            f"document is larger than the {max_bytes // (1024 * 1024)} MB limit", file=source
        )
    reject_declarations(data, source, what=what)
    events = iterparse(data)
    depth = 0
    root: etree._Element | None = None
    try:
        for event, element in events:
            if event == "start":
                depth += 1
                if depth == 1:
                    root = element
                    yield element
                continue
            depth -= 1
            if depth == 1 and root is not None:
                yield element
                # Freed once handled: the streamed document never holds more than one child.
                element.clear(keep_tail=False)
                root.remove(element)
    except etree.XMLSyntaxError as exc:
        # iterparse reports some errors (undefined entities) as "no element found" at line 0;
        # libxml2's own last error says what and where.
        last = exc.error_log.last_error
        message, line = (last.message, last.line) if last is not None else (exc.msg, exc.lineno)
        raise ScenarioError(f"malformed XML: {message}", file=source, line=line) from exc


def iterparse(data: bytes) -> Iterator[tuple[str, etree._Element]]:
    """lxml's start and end events over ``data``, hardened as :func:`parse_bytes` is: no entity
    expansion, DTD loading, network or huge trees; comments and processing instructions dropped.
    The caller checks the size and :func:`reject_declarations` first."""
    events: Iterator[tuple[str, etree._Element]] = etree.iterparse(
        io.BytesIO(data),
        events=("start", "end"),
        resolve_entities=False,
        no_network=True,
        load_dtd=False,
        huge_tree=False,
        remove_comments=True,
        remove_pis=True,
        collect_ids=False,
    )
    return events


def parse_file(path: Path, *, max_bytes: int = MAX_BYTES, what: str = "scenario") -> Element:
    """Read and safely parse the XML file at ``path``; return its root element."""
    data = read_bytes(path, max_bytes=max_bytes)
    return parse_bytes(data, source=str(path), max_bytes=max_bytes, what=what)


def reject_declarations(data: bytes, source: str, *, what: str = "scenario") -> None:
    """Refuse any DOCTYPE or ENTITY declaration, before a parser ever sees the document."""
    # Encodings other than UTF-8/ASCII are re-encoded so the scan cannot be dodged with UTF-16.
    text = data
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            text = data.decode("utf-16").encode("utf-8")
        except UnicodeDecodeError as exc:
            raise ScenarioError("undecodable UTF-16 document", file=source) from exc
    match = _DECLARATION.search(text)
    if match:
        line = text.count(b"\n", 0, match.start()) + 1
        kind = match.group(1).decode("ascii").upper()
        raise ScenarioError(
            f"{kind} declarations are not allowed in {what} files (entity expansion and "
            "external entities are a security risk)",
            file=source,
            line=line,
        )


def _strip_namespaces(root: etree._Element) -> None:
    # OpenSCENARIO has no target namespace, but some writers add a default xmlns; tags are
    # compared by local name everywhere else.
    for node in root.iter():
        tag = node.tag
        if isinstance(tag, str) and tag.startswith("{"):
            node.tag = tag.split("}", 1)[1]
