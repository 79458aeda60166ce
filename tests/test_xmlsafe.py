"""Hostile and broken XML is rejected before it can do harm.

Covers: billion laughs (internal entity expansion), external entities (file and network), a
DOCTYPE without entities, a UTF-16 document hiding a DOCTYPE, oversize files, malformed XML with a
line number, namespaced documents being accepted, and that load_scenario applies all of it.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator import xmlsafe
from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import load_scenario

BILLION_LAUGHS = b"""<?xml version="1.0"?>
<!DOCTYPE lolz [
 <!ENTITY lol "lol">
 <!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
 <!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">
 <!ENTITY lol4 "&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;">
]>
<OpenSCENARIO><FileHeader description="&lol4;" revMajor="1" revMinor="0"/></OpenSCENARIO>
"""

EXTERNAL_FILE = b"""<?xml version="1.0"?>
<!DOCTYPE x [ <!ENTITY secret SYSTEM "file:///etc/passwd"> ]>
<OpenSCENARIO><FileHeader description="&secret;" revMajor="1" revMinor="0"/></OpenSCENARIO>
"""

EXTERNAL_NETWORK = b"""<?xml version="1.0"?>
<!DOCTYPE OpenSCENARIO SYSTEM "http://example.invalid/evil.dtd">
<OpenSCENARIO/>
"""


@pytest.mark.parametrize(
    "data", [BILLION_LAUGHS, EXTERNAL_FILE, EXTERNAL_NETWORK], ids=["laughs", "file", "network"]
)
def test_rejects_doctype_and_entities(data: bytes) -> None:
    with pytest.raises(ScenarioError, match="not allowed") as info:
        xmlsafe.parse_bytes(data, source="evil.xosc")
    assert info.value.file == "evil.xosc"
    assert info.value.line == 2


def test_rejects_doctype_hidden_in_utf16() -> None:
    data = EXTERNAL_FILE.decode().replace('version="1.0"', 'version="1.0" encoding="UTF-16"')
    with pytest.raises(ScenarioError, match="DOCTYPE"):
        xmlsafe.parse_bytes(data.encode("utf-16"), source="evil.xosc")


def test_rejects_oversize(tmp_path: Path) -> None:
    path = tmp_path / "big.xosc"
    path.write_bytes(b"<OpenSCENARIO>" + b" " * 2048 + b"</OpenSCENARIO>")
    with pytest.raises(ScenarioError, match="larger than"):
        xmlsafe.parse_file(path, max_bytes=1024)
    assert xmlsafe.parse_file(path, max_bytes=4096).tag == "OpenSCENARIO"


def test_default_limit_is_20_mb() -> None:
    assert xmlsafe.MAX_BYTES == 20 * 1024 * 1024
    with pytest.raises(ScenarioError, match="20 MB"):
        xmlsafe.parse_bytes(b" " * (xmlsafe.MAX_BYTES + 1), source="big.xosc")


def test_malformed_xml_names_line() -> None:
    with pytest.raises(ScenarioError, match="malformed XML") as info:
        xmlsafe.parse_bytes(b"<OpenSCENARIO>\n<FileHeader>\n</OpenSCENARIO>", source="bad.xosc")
    assert info.value.line == 3


def test_keeps_lines_strips_comments_and_namespaces() -> None:
    root = xmlsafe.parse_bytes(
        b'<?xml version="1.0"?>\n<OpenSCENARIO xmlns="urn:x">\n<!-- c -->\n<FileHeader/>\n'
        b"</OpenSCENARIO>",
        source="ok.xosc",
    )
    assert root.tag == "OpenSCENARIO"
    children = list(root)
    assert [c.tag for c in children] == ["FileHeader"]
    assert children[0].sourceline == 4


def test_missing_file_is_scenario_error(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError, match="cannot read"):
        xmlsafe.parse_file(tmp_path / "absent.xosc")


def test_load_scenario_rejects_hostile_file(tmp_path: Path) -> None:
    path = tmp_path / "laughs.xosc"
    path.write_bytes(BILLION_LAUGHS)
    with pytest.raises(ScenarioError, match="DOCTYPE declarations are not allowed"):
        load_scenario(path)


def test_streamed_parsing_applies_the_same_protections() -> None:
    for hostile in (BILLION_LAUGHS, EXTERNAL_FILE):
        with pytest.raises(ScenarioError, match="DOCTYPE"):
            list(xmlsafe.stream_children(hostile, source="x.xodr"))
    with pytest.raises(ScenarioError, match="Entity 'undefined' not defined") as caught:
        list(xmlsafe.stream_children(b"<a>\n<b v='&undefined;'/></a>", source="x.xodr"))
    assert caught.value.line == 2
    with pytest.raises(ScenarioError, match="limit"):
        list(xmlsafe.stream_children(b"<a/>", source="x.xodr", max_bytes=2))
    with pytest.raises(ScenarioError, match="malformed") as caught:
        list(xmlsafe.stream_children(b"<a>\n<b>\n</a>", source="x.xodr"))
    assert caught.value.line == 3


def test_streamed_children_are_freed_after_use() -> None:
    data = b"<root k='v'>\n<x n='1'><y/></x>\n<x n='2'/>\n</root>"
    stream = xmlsafe.stream_children(data, source="s.xml")
    root = next(stream)
    assert (root.tag, root.get("k")) == ("root", "v")
    seen = []
    previous = None
    for child in stream:
        seen.append((child.get("n"), child.sourceline, len(list(child))))
        assert previous is None or (previous not in list(root) and len(previous) == 0)
        previous = child
    assert seen == [("1", 2, 1), ("2", 3, 0)]


def test_libxml2_messages_become_one_line() -> None:
    # libxml2 ends some messages with a newline ("Invalid character: Char 0x0 out of allowed
    # range\n"): a two-line Invalid reason, found by fuzzing (issue 29).
    data = b"<?xml version='1.0'?>\n<a>\x00</a>"
    with pytest.raises(ScenarioError) as caught:
        xmlsafe.parse_bytes(data, source="bad\nname.xosc")
    message = str(caught.value)
    assert "\n" not in message and "Char 0x0 out of allowed range" in message
    assert message.endswith("(bad\\x0aname.xosc, line 2)")
