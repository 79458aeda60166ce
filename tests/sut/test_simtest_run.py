"""``simtest run`` with an external SUT: the example campaign's sidecar SUT is started as a local
process per scenario (there is no pod); the verdicts equal the in-process smoke campaign's and
every result names the SUT that produced it, its image by digest where this machine knows it (a
pinned reference, the build script's index) and ``unknown`` otherwise; the endpoint a pod's
template names (``SIMTEST_SUT_ENDPOINT``, via the settings) reaches the run requests."""

from __future__ import annotations

import dataclasses
import datetime
import json
from pathlib import Path

from click.testing import CliRunner

from simtest_operator import provenance
from simtest_operator.cli.main import cli
from simtest_operator.drivermodel import ExternalSut, Launch, SutConfig
from simtest_operator.runner import entrypoint, fakes, preparing, suts
from simtest_operator.settings import SUT_ENDPOINT, Settings
from simtest_operator.sut import runs
from simtest_operator.sut.client import Identity
from tests.runner import podsupport

REPO = Path(__file__).resolve().parents[2]


def verdicts(out: Path) -> dict[str, tuple[str, dict[str, str]]]:
    found = {}
    for path in sorted(out.glob("scenarios/*/result.json")):
        result = json.loads(path.read_text(encoding="utf-8"))
        found[result["scenarioId"]] = (result["verdict"], result["versions"])
    return found


def test_the_external_sut_campaign_runs_locally_like_the_in_process_one(tmp_path: Path) -> None:
    found = {}
    for name in ("smoke", "external-sut"):
        manifest = REPO / "scenarios" / f"{name}-campaign.yaml"
        arguments = ["run", str(manifest), "-o", str(tmp_path / name), "-j", "1", "--plain"]
        result = CliRunner().invoke(cli, arguments)
        assert result.exit_code == 1, result.output  # one scenario fails, in both
        found[name] = verdicts(tmp_path / name)
    inside, outside = found["smoke"], found["external-sut"]
    index = Settings.from_env().cache.image_index  # built here or not: the result says which
    known_here = provenance.built_image_id("ghcr.io/simtest-dev/simtest-runner:0.1.0", index)
    known_here = known_here or "unknown"
    assert len(inside) == 6
    assert {k: v[0] for k, v in outside.items()} == {k: v[0] for k, v in inside.items()}
    for _, versions in outside.values():
        assert versions["sut.reported"] == "simtest-reference-sut 1.0.0"
        assert versions["sut.launch"] == "sidecar"
        assert versions["sut.image"] == "ghcr.io/simtest-dev/simtest-runner:0.1.0"
        assert versions["sut.imageID"] == known_here
    assert all("sut.reported" not in versions for _, versions in inside.values())


DIGEST = "sha256:" + "5e" * 32
IMAGE_ID = "sha256:" + "1f" * 32


def test_the_image_digest_is_named_only_where_it_is_known(tmp_path: Path) -> None:
    index = tmp_path / "images.json"
    index.write_text(json.dumps({"images": {"acme/planner:2": {"digest": DIGEST, "id": IMAGE_ID}}}))

    def recorded(image: str | None, launch: Launch = Launch.SIDECAR) -> dict[str, str]:
        external = ExternalSut(launch=launch, image=image, command=("planner",))
        sut = suts.with_image_id(SutConfig(name="planner", external=external), index)
        return runs.provenance(sut, Identity(name="planner", version="2"))

    assert recorded("acme/planner:2")["sut.imageID"] == IMAGE_ID  # as the node reports it
    assert recorded(f"ghcr.io/acme/planner@{DIGEST}")["sut.imageID"] == (
        f"ghcr.io/acme/planner@{DIGEST}"
    )
    assert recorded("acme/planner:3")["sut.imageID"] == "unknown"
    assert "sut.imageID" not in recorded(None, Launch.LOCAL)  # no image, nothing to name
    plain = SutConfig(name="model")
    assert suts.with_image_id(plain, index) is plain


def test_the_endpoint_a_pod_is_given_reaches_its_run_requests(tmp_path: Path) -> None:
    """``SIMTEST_SUT_ENDPOINT`` is read into the settings once and applied where run requests are
    built: the pod's runner (a sidecar on loopback) and ``simtest run`` (a user's own stack); a
    SUT the runner starts itself is not redirected, and without the variable nothing changes."""
    env = {"HOME": str(tmp_path / "home"), SUT_ENDPOINT: " 127.0.0.1:7600 "}
    in_pod = Settings.from_env(env)
    assert in_pod.sut_endpoint == "127.0.0.1:7600"
    job = podsupport.job(tmp_path / "pod", {"a": "pass"})
    sidecar = {"name": "planner", "external": {"image": "acme/planner:2", "port": 7600}}
    job = dataclasses.replace(job, spec=dataclasses.replace(job.spec, sut=sidecar), settings=in_pod)
    scenario = job.spec.scenarios[0]
    request = entrypoint.requests_for(job, scenario, Path(scenario.source.removeprefix("file://")))
    assert request.sut.external is not None
    assert (request.sut.external.launch, request.sut.external.endpoint) == (
        Launch.SIDECAR, "127.0.0.1:7600")  # fmt: skip

    manifest = REPO / "scenarios" / "external-sut-campaign.yaml"
    local = preparing.LocalRunRequest(
        manifest=manifest, output=tmp_path / "out", settings=in_pod, execute=fakes.execute
    )
    plan = preparing.prepare(local, now=datetime.datetime.now(datetime.UTC))
    assert plan.sut.external is not None and plan.sut.external.endpoint == "127.0.0.1:7600"

    started = SutConfig(external=ExternalSut(launch=Launch.LOCAL, command=("planner",)))
    assert suts.reached_here(started, in_pod) == started
    nowhere = Settings.from_env({"HOME": str(tmp_path / "home"), SUT_ENDPOINT: ""})
    plain = SutConfig(external=ExternalSut(launch=Launch.ENDPOINT, endpoint="stack:7461"))
    assert nowhere.sut_endpoint is None and suts.reached_here(plain, nowhere) == plain
