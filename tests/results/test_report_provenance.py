"""The report names what ran: simulator and lock digest in the header, versions per scenario.

Covers: a ``simtest run`` campaign (the row holds the SUMO/engine version and the record with the
lock digest) shows both in the header, the lock cut to 12 hex digits with the full digest as its
title; a cluster campaign (the row names the runner image) keeps the image and adds what its
pods recorded (SUMO version, lock); scenarios that disagree on the lock show each; without any
record the header says ``?`` and shows no lock; the developer view labels versions and digests.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import lxml.html

from simtest_operator.results import reporting, reportmodel
from tests.results.resultdata import T0, sample_run

SUMO = "SUMO 1.28.0 (simtest engine 0.1.0)"
LOCK = "sha256:" + "0123456789ab" + "cd" * 26
OTHER_LOCK = "sha256:" + "fedcba987654" + "32" * 26
IMAGE = "ghcr.io/simtest-dev/simtest-runner:0.1.0"


def _run(
    *, simulator: str, settings: Mapping[str, object], versions: Mapping[str, str]
) -> reportmodel.Run:
    record, stored, listed = sample_run()
    info = dataclasses.replace(record.info, simulator_version=simulator, settings=settings)
    outcomes = tuple(
        dataclasses.replace(s, outcome=dataclasses.replace(s.outcome, versions=versions))
        for s in stored
    )
    return reportmodel.Run(
        campaign=dataclasses.replace(record, info=info), outcomes=outcomes, scenarios=tuple(listed)
    )


def _header(report: reportmodel.Report) -> lxml.html.HtmlElement:
    page = lxml.html.fromstring(reporting.render(report))
    (meta,) = page.xpath("//header/div[@class='meta']")
    return meta


def test_a_local_run_names_sumo_and_the_lock() -> None:
    record = {"simulator": SUMO, "sumo": "1.28.0", "lock": LOCK}
    run = _run(simulator=SUMO, settings={"parallel": 2, "versions": record}, versions=record)
    report = reportmodel.build(run, generated_at=T0)
    assert report.provenance == reportmodel.Provenance(simulator=SUMO, lock=LOCK)
    meta = _header(report)
    assert meta.get_element_by_id("simulator").text_content() == SUMO
    assert not meta.xpath(".//*[@id='engine']")
    lock = meta.get_element_by_id("lock")
    assert (lock.text_content(), lock.get("title")) == ("sha256:0123456789ab", LOCK)


def test_a_cluster_campaign_keeps_its_image_and_adds_what_the_pods_ran() -> None:
    run = _run(
        simulator=IMAGE,
        settings={"batchSize": 10},
        versions={"simulator": SUMO, "lock": LOCK, "sut": "idm-driver 1.4.0"},
    )
    report = reportmodel.build(run, generated_at=T0)
    assert report.provenance == reportmodel.Provenance(simulator=IMAGE, engine=SUMO, lock=LOCK)
    meta = _header(report)
    assert meta.get_element_by_id("simulator").text_content() == IMAGE
    assert meta.get_element_by_id("engine").text_content() == SUMO
    assert meta.get_element_by_id("lock").text_content() == "sha256:0123456789ab"


def test_scenarios_that_disagree_on_the_lock_show_each() -> None:
    run = _run(simulator=IMAGE, settings={}, versions={"lock": LOCK})
    first = run.outcomes[0]
    odd = dataclasses.replace(first.outcome, versions={"lock": OTHER_LOCK})
    run = dataclasses.replace(run, outcomes=(dataclasses.replace(first, outcome=odd),
                                             *run.outcomes[1:]))  # fmt: skip
    provenance = reportmodel.build(run, generated_at=T0).provenance
    assert provenance.short_lock == "sha256:0123456789ab / sha256:fedcba987654"


def test_without_a_record_the_header_says_so() -> None:
    report = reportmodel.build(
        _run(simulator="", settings={}, versions={"engine": "fake"}), generated_at=T0
    )
    meta = _header(report)
    assert meta.get_element_by_id("simulator").text_content() == "?"
    assert not meta.xpath(".//*[@id='lock'] | .//*[@id='engine']")


def test_the_developer_view_labels_versions_and_digests() -> None:
    record = {"simulator": SUMO, "sumo": "1.28.0", "lock": LOCK, "installed": OTHER_LOCK}
    report = reportmodel.build(
        _run(simulator=SUMO, settings={"versions": record}, versions=record), generated_at=T0
    )
    assert dict(report.scenarios[0].versions) == {
        "installed digest": OTHER_LOCK,
        "lock digest": LOCK,
        "simulator version": SUMO,
        "sumo version": "1.28.0",
    }


def test_the_developer_view_names_the_sut_that_produced_the_result() -> None:
    digest = "ghcr.io/acme/planner@sha256:" + "5e" * 32
    record = {
        "sut": "acme-planner 2.1.0",
        "sut.reported": "acme-planner 2.1.0-rc1",
        "sut.configHash": "sha256:0123456789abcdef",
        "sut.image": "ghcr.io/acme/planner:2.1.0",
        "sut.imageID": digest,
        "sut.launch": "sidecar",
    }
    report = reportmodel.build(_run(simulator=SUMO, settings={}, versions=record), generated_at=T0)
    assert dict(report.scenarios[0].versions) == {
        "sut version": "acme-planner 2.1.0",
        "SUT as it reported itself": "acme-planner 2.1.0-rc1",
        "SUT config hash": "sha256:0123456789abcdef",
        "SUT image": "ghcr.io/acme/planner:2.1.0",
        "SUT image digest": digest,
        "SUT launched as": "sidecar",
    }
