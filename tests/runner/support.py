"""Helpers for runner tests: fake-engine scenario files and process liveness checks."""

from __future__ import annotations

from pathlib import Path

from simtest_operator.scenarios import PinnedScenario, sha256_hex


def fake_xosc(behaviour: str, *, tags: str = "", category: str = "") -> str:
    """A scenario file telling the fake engine how to behave (``simtest:fake``)."""
    props = f'<Property name="simtest:fake" value="{behaviour}"/>'
    if tags:
        props += f'<Property name="simtest:tags" value="{tags}"/>'
    if category:
        props += f'<Property name="simtest:category" value="{category}"/>'
    return (
        '<?xml version="1.0"?>\n<OpenSCENARIO><FileHeader revMajor="1" revMinor="1" '
        f'date="2024-01-01T00:00:00" description="fake {behaviour}" author="t">'
        f"<Properties>{props}</Properties></FileHeader><Storyboard/></OpenSCENARIO>\n"
    )


def write_scenarios(folder: Path, behaviours: dict[str, str]) -> list[PinnedScenario]:
    """One file per (name -> behaviour); returns them pinned, in the given order."""
    folder.mkdir(parents=True, exist_ok=True)
    pinned = []
    for name, behaviour in behaviours.items():
        path = folder / f"{name}.xosc"
        path.write_text(fake_xosc(behaviour))
        pinned.append(
            PinnedScenario(id=f"{name}.xosc", source=path.as_uri(), sha256=sha256_hex(
                path.read_bytes()))
        )  # fmt: skip
    return pinned


def alive(pid: int) -> bool:
    """Whether ``pid`` is a running (not zombie) process."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except FileNotFoundError:
        return False
    state = next((line for line in status.splitlines() if line.startswith("State:")), "")
    return "Z" not in state.split()[1:2]


def campaign_manifest(
    name: str = "demo", *, source: str = "suite", batch_size: int = 2, timeout: int = 20,
    retries: int = 1, extra: str = "",
) -> str:  # fmt: skip
    """A TestCampaign manifest over a path source."""
    return f"""apiVersion: simtest.dev/v1alpha1
kind: TestCampaign
metadata:
  name: {name}
spec:
  scenarios:
    sources:
      - path: {source}
  execution:
    batchSize: {batch_size}
    timeoutSeconds: {timeout}
    retries: {retries}
{extra}"""


def write_campaign(folder: Path, behaviours: dict[str, str], **kwargs: object) -> Path:
    """A manifest in ``folder`` plus a ``suite`` of fake-engine scenarios; returns the manifest."""
    suite = folder / "suite"
    suite.mkdir(parents=True, exist_ok=True)
    for name, behaviour in behaviours.items():
        path = suite / f"{name}.xosc"
        path.parent.mkdir(parents=True, exist_ok=True)
        category = name.split("/")[0] if "/" in name else "misc"
        path.write_text(fake_xosc(behaviour, tags="fake", category=category))
    manifest = folder / "campaign.yaml"
    manifest.write_text(campaign_manifest(**kwargs))  # type: ignore[arg-type]
    return manifest
