"""Freezing a campaign's selection into the frozen list.

Covers: include/exclude globs, catalog files left out with a note, the tag/label selector over
FileHeader properties, a file with an unreadable header kept (it will run as Invalid) with a note,
a ParameterValueDistribution expanded into one pinned run per assignment (ids with suffix, URI and
sha256 of the referenced scenario, distribution values over campaign overrides), a broken
distribution kept, id clashes across sources suffixed, and the list being deterministic.
"""

from __future__ import annotations

from pathlib import Path

from simtest_operator.runner import resolving
from simtest_operator.scenarios import FetchContext, PathSource, Selection, Selector, sha256_hex

HEADER = '<FileHeader revMajor="1" revMinor="2" date="2024-01-01T00:00:00" description="{d}" ' \
    'author="t"><Properties>{props}</Properties></FileHeader>'  # fmt: skip


def scenario(description: str, *, tags: str = "", category: str = "") -> str:
    props = f'<Property name="simtest:tags" value="{tags}"/>' if tags else ""
    props += f'<Property name="simtest:category" value="{category}"/>' if category else ""
    return (
        f"<?xml version='1.0'?><OpenSCENARIO>{HEADER.format(d=description, props=props)}"
        '<ParameterDeclarations><ParameterDeclaration name="Speed" parameterType="double" '
        'value="10"/><ParameterDeclaration name="Gap" parameterType="double" value="5"/>'
        "</ParameterDeclarations><Storyboard/></OpenSCENARIO>"
    )


CATALOG = f"<OpenSCENARIO>{HEADER.format(d='cat', props='')}<Catalog name='V'/></OpenSCENARIO>"
DISTRIBUTION = (
    f"<OpenSCENARIO>{HEADER.format(d='dist', props='')}<ParameterValueDistribution>"
    '<ScenarioFile filepath="base.xosc"/><Deterministic>'
    '<DeterministicSingleParameterDistribution parameterName="Speed"><DistributionSet>'
    '<Element value="20"/><Element value="30"/><Element value="40"/></DistributionSet>'
    "</DeterministicSingleParameterDistribution></Deterministic></ParameterValueDistribution>"
    "</OpenSCENARIO>"
)


def suite(root: Path) -> Path:
    files = {
        "follow/a.xosc": scenario("a", tags="highway,day", category="following"),
        "follow/b.xosc": scenario("b", tags="highway,night", category="following"),
        "cut-in/c.xosc": scenario("c", tags="highway,day", category="cut-in"),
        "wip/d.xosc": scenario("d"),
        "Catalogs/vehicles.xosc": CATALOG,
        "broken.xosc": "<OpenSCENARIO><FileHeader",
        "dist/base.xosc": scenario("base", tags="day"),
        "dist/speeds.xosc": DISTRIBUTION.replace("<Properties></Properties>",
                                                 '<Properties><Property name="simtest:tags" '
                                                 'value="day"/></Properties>'),
        "roads/r.xodr": "<OpenDRIVE/>",
    }  # fmt: skip
    for name, text in files.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text)
    return root


def ctx(tmp_path: Path) -> FetchContext:
    return FetchContext(base_dir=tmp_path, cache_dir=tmp_path / "cache")


def test_globs_catalogs_broken_and_distributions(tmp_path: Path) -> None:
    suite(tmp_path / "s")
    selection = Selection(
        sources=(PathSource(path="s"),), exclude=("wip/**",), overrides={"Gap": "7", "Speed": "1"}
    )
    frozen = resolving.freeze(selection, ctx(tmp_path), campaign="c", seed=1)
    ids = [s.id for s in frozen.scenarios]
    dist_ids = [i for i in ids if i.startswith("dist/speeds.xosc#")]
    assert ids[:4] == ["broken.xosc", "cut-in/c.xosc", "dist/base.xosc", *dist_ids[:1]]
    assert len(dist_ids) == 3 and ids[-2:] == ["follow/a.xosc", "follow/b.xosc"]
    runs = [s for s in frozen.scenarios if s.id in dist_ids]
    base = tmp_path / "s/dist/base.xosc"
    assert {r.source for r in runs} == {base.as_uri()}
    assert {r.sha256 for r in runs} == {sha256_hex(base.read_bytes())}
    assert sorted(r.overrides["Speed"] for r in runs) == ["20", "30", "40"]
    assert {r.overrides["Gap"] for r in runs} == {"7"}, "campaign overrides stay underneath"
    assert any("catalog files" in n for n in frozen.notes)
    assert any(n.startswith("broken.xosc: header unreadable, kept") for n in frozen.notes)
    again = resolving.freeze(selection, ctx(tmp_path), campaign="c", seed=1)
    assert again == frozen, "deterministic"


def test_selector(tmp_path: Path) -> None:
    suite(tmp_path / "s")
    selection = Selection(
        sources=(PathSource(path="s"),),
        include=("follow/**", "cut-in/**", "dist/*.xosc"),
        selector=Selector(tags=("day",), labels={"category": "following"}),
    )
    frozen = resolving.freeze(selection, ctx(tmp_path), campaign="c")
    assert [s.id for s in frozen.scenarios] == ["follow/a.xosc"]
    only_tags = Selection(sources=(PathSource(path="s"),), include=("**/*.xosc",),
                          exclude=("broken.xosc",), selector=Selector(tags=("night",)))  # fmt: skip
    assert [s.id for s in resolving.freeze(only_tags, ctx(tmp_path), campaign="c").scenarios] == [
        "follow/b.xosc"
    ]


def test_broken_distribution_is_kept_and_id_clash_suffixed(tmp_path: Path) -> None:
    root = suite(tmp_path / "s")
    (root / "dist/base.xosc").unlink()
    other = tmp_path / "t/follow"
    other.mkdir(parents=True)
    (other / "a.xosc").write_text(scenario("other a"))
    selection = Selection(
        sources=(PathSource(path="s"), PathSource(path="t")), include=("dist/*.xosc", "follow/a*")
    )
    frozen = resolving.freeze(selection, ctx(tmp_path), campaign="c")
    assert [s.id for s in frozen.scenarios] == ["dist/speeds.xosc", "follow/a.xosc",
                                                "follow/a.xosc~2"]  # fmt: skip
    assert any("distribution cannot be expanded" in n for n in frozen.notes)
