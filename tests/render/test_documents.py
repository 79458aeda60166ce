"""Helm-style deep merge, canonical JSON and hashes.

Covers: nested mappings merge, lists and scalars replace, None removes, inputs are not mutated;
canonical JSON ignores key order; YAML output is sorted and stable.
"""

from __future__ import annotations

from simtest_operator.render import documents


def test_deep_merge_follows_helm() -> None:
    base = {"a": {"b": 1, "c": [1, 2]}, "d": 1, "e": {"f": 1}}
    override = {"a": {"c": [3], "x": {"y": 1}}, "d": None, "e": "scalar"}
    merged = documents.deep_merge(base, override)
    assert merged == {"a": {"b": 1, "c": [3], "x": {"y": 1}}, "e": "scalar"}
    assert base == {"a": {"b": 1, "c": [1, 2]}, "d": 1, "e": {"f": 1}}


def test_canonical_forms_ignore_key_order() -> None:
    assert (
        documents.canonical_json({"b": 1, "a": [1, {"d": 2, "c": 1}]})
        == '{"a":[1,{"c":1,"d":2}],"b":1}'
    )
    assert documents.content_hash({"a": 1, "b": 2}) == documents.content_hash({"b": 2, "a": 1})
    assert documents.to_yaml({"b": 1, "a": {"d": 1, "c": 2}}) == "a:\n  c: 2\n  d: 1\nb: 1\n"
