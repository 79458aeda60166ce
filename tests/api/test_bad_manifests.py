"""Bad input is rejected with a message naming the field: every case of the shared table
(testdata/bad-manifests.yaml) through the local validator; the base manifest is accepted."""

from __future__ import annotations

import pytest

from simtest_operator.api import v1alpha1
from tests.api import badmanifests

CASES = badmanifests.load()


def test_table_is_large_enough() -> None:
    assert len(CASES) >= 15
    assert len({case.id for case in CASES}) == len(CASES)


def test_base_manifest_is_valid() -> None:
    manifest = v1alpha1.parse_campaign(badmanifests.base())
    assert manifest.name == "bad-input"
    assert manifest.spec.execution.batch_size == 9


@pytest.mark.parametrize("case", CASES, ids=[case.id for case in CASES])
def test_rejected_naming_the_field(case: badmanifests.BadManifest) -> None:
    with pytest.raises(v1alpha1.ManifestError) as caught:
        v1alpha1.parse_campaign(case.manifest, source=f"{case.id}.yaml")
    message = str(caught.value)
    assert case.names_field(message), f"{case.field!r} not named in: {message}"
