"""Safe archive extraction: good tar/zip trees unpack; hostile ones are refused and leave nothing.

Covers zip slip (``..``), absolute names, backslash names, tar symlinks and hard links escaping the
folder (also via an absolute target), an internal symlink that is allowed, zip symlink entries,
device members, member-count and total-size limits (also for a highly compressed zip), corrupt
archives and format sniffing — each with Python's ``data`` extraction filter and without it (the
runner image's Debian Python 3.11.2 has none; a real-node campaign found that out).
"""

from __future__ import annotations

import io
import stat
import tarfile
import zipfile
from pathlib import Path

import pytest

from simtest_operator.errors import SourceError
from simtest_operator.scenarios import archives
from simtest_operator.scenarios.specs import SourceLimits


@pytest.fixture(autouse=True, params=[True, False], ids=["data-filter", "no-filter"])
def data_filter(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> None:
    if request.param and not hasattr(tarfile, "data_filter"):
        pytest.skip("this Python has no tar extraction filters")
    monkeypatch.setattr(archives, "HAS_DATA_FILTER", request.param)


def make_tar(path: Path, members: list[tuple[str, str, bytes | str]]) -> Path:
    """members: (kind, name, data or link target); kind in file, dir, sym, hard, dev."""
    with tarfile.open(path, "w:gz") as tar:
        for kind, name, payload in members:
            info = tarfile.TarInfo(name)
            if kind == "file":
                assert isinstance(payload, bytes)
                info.size = len(payload)
                tar.addfile(info, io.BytesIO(payload))
                continue
            if kind == "dir":
                info.type = tarfile.DIRTYPE
            elif kind == "sym":
                info.type, info.linkname = tarfile.SYMTYPE, str(payload)
            elif kind == "hard":
                info.type, info.linkname = tarfile.LNKTYPE, str(payload)
            elif kind == "dev":
                info.type = tarfile.CHRTYPE
            tar.addfile(info)
    return path


def make_zip(path: Path, members: list[tuple[str, bytes]], *, symlink: str | None = None) -> Path:
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zipped:
        for name, data in members:
            zipped.writestr(name, data)
        if symlink is not None:
            info = zipfile.ZipInfo(symlink)
            info.external_attr = (stat.S_IFLNK | 0o777) << 16
            zipped.writestr(info, "/etc/passwd")
    return path


def test_good_tar_and_zip_unpack(tmp_path: Path) -> None:
    tar = make_tar(tmp_path / "a.tgz", [("dir", "suite", b""), ("file", "suite/a.xosc", b"<a/>"),
                                        ("file", "./suite/sub/b.xosc", b"<b/>"),
                                        ("sym", "suite/link.xosc", "a.xosc")])  # fmt: skip
    assert archives.extract(tar, tmp_path / "t", limits=SourceLimits()) == 2
    assert (tmp_path / "t/suite/sub/b.xosc").read_bytes() == b"<b/>"
    assert (tmp_path / "t/suite/link.xosc").read_bytes() == b"<a/>"
    zipped = make_zip(tmp_path / "a.zip", [("x/a.xosc", b"<a/>"), ("x/", b"")])
    assert archives.extract(zipped, tmp_path / "z", limits=SourceLimits()) == 1
    assert (tmp_path / "z/x/a.xosc").read_bytes() == b"<a/>"


@pytest.mark.parametrize(
    ("members", "message"),
    [
        ([("file", "../evil.xosc", b"x")], "outside the archive folder"),
        ([("file", "ok/../../evil.xosc", b"x")], "outside the archive folder"),
        ([("file", "/tmp/evil.xosc", b"x")], "absolute path"),
        ([("file", "a\\..\\evil.xosc", b"x")], "backslash"),
        ([("sym", "escape", "../../etc")], "escapes the archive folder"),
        ([("sym", "sub/escape", "../../x")], "escapes the archive folder"),
        ([("sym", "abs", "/etc/passwd")], "absolute path"),
        ([("hard", "hl", "../outside")], "escapes the archive folder"),
        ([("hard", "hl", "/etc/passwd")], "absolute path"),
        ([("dev", "tty", b"")], "device"),
    ],
)
def test_hostile_tar_members_are_refused(
    tmp_path: Path, members: list[tuple[str, str, bytes | str]], message: str
) -> None:
    tar = make_tar(tmp_path / "evil.tgz", [("file", "good.xosc", b"<a/>"), *members])
    dest = tmp_path / "out"
    with pytest.raises(SourceError, match=message):
        archives.extract(tar, dest, limits=SourceLimits())
    assert not dest.exists(), "a refused archive leaves no partial tree"
    assert not (tmp_path / "evil.xosc").exists()


def test_symlink_then_write_through_it_stays_inside(tmp_path: Path) -> None:
    # A link to a folder inside, then a file "through" it: allowed, and lands inside.
    tar = make_tar(tmp_path / "a.tgz", [("dir", "real", b""), ("sym", "alias", "real"),
                                        ("file", "alias/f.xosc", b"<f/>")])  # fmt: skip
    dest = tmp_path / "out"
    try:
        archives.extract(tar, dest, limits=SourceLimits())
    except SourceError:
        assert not dest.exists()  # refusing is acceptable too; escaping is not
    else:
        assert (dest / "real/f.xosc").read_bytes() == b"<f/>"
    assert not (tmp_path / "f.xosc").exists()


@pytest.mark.parametrize(
    ("name", "message"),
    [("../slip.xosc", "outside"), ("/abs.xosc", "absolute"), ("C:/x.xosc", "absolute")],
)
def test_zip_slip_is_refused(tmp_path: Path, name: str, message: str) -> None:
    zipped = make_zip(tmp_path / "evil.zip", [("good.xosc", b"<a/>"), (name, b"x")])
    dest = tmp_path / "deep/out"
    with pytest.raises(SourceError, match=message):
        archives.extract(zipped, dest, limits=SourceLimits())
    assert not dest.exists()
    assert not (tmp_path / "deep/slip.xosc").exists()


def test_zip_symlink_entry_is_refused(tmp_path: Path) -> None:
    zipped = make_zip(tmp_path / "l.zip", [("a.xosc", b"<a/>")], symlink="passwd.xosc")
    with pytest.raises(SourceError, match="symbolic link"):
        archives.extract(zipped, tmp_path / "out", limits=SourceLimits())


def test_member_count_limit(tmp_path: Path) -> None:
    members = [(f"f{i}.xosc", b"x") for i in range(11)]
    limits = SourceLimits(max_archive_members=10)
    with pytest.raises(SourceError, match="more than 10 archive members"):
        archives.extract(make_zip(tmp_path / "m.zip", members), tmp_path / "z", limits=limits)
    tar_members = [("file", f"f{i}.xosc", b"x") for i in range(11)]
    with pytest.raises(SourceError, match="more than 10 archive members"):
        archives.extract(make_tar(tmp_path / "m.tgz", tar_members), tmp_path / "t", limits=limits)  # type: ignore[arg-type]


def test_total_size_limit_counts_real_bytes(tmp_path: Path) -> None:
    # 4 MB of zeros compress to a few KB: the limit applies to what is written, not the download.
    big = b"\0" * (4 * 1024 * 1024)
    zipped = make_zip(tmp_path / "bomb.zip", [("a.xosc", big)])
    assert zipped.stat().st_size < 64 * 1024
    limits = SourceLimits(max_extracted_bytes=1024 * 1024)
    with pytest.raises(SourceError, match="exceeds the 1048576 byte limit"):
        archives.extract(zipped, tmp_path / "z", limits=limits)
    assert not (tmp_path / "z").exists()
    tar = make_tar(tmp_path / "bomb.tgz", [("file", "a.xosc", big)])
    with pytest.raises(SourceError, match="exceeds"):
        archives.extract(tar, tmp_path / "t", limits=limits)


def test_corrupt_and_unknown_archives(tmp_path: Path) -> None:
    good = make_zip(tmp_path / "g.zip", [("a.xosc", b"<a/>" * 1000)])
    broken = tmp_path / "broken.zip"
    data = good.read_bytes()
    broken.write_bytes(data[: len(data) // 2])
    with pytest.raises(SourceError, match="corrupt zip"):
        archives.extract(broken, tmp_path / "b", limits=SourceLimits())
    text = tmp_path / "plain.xosc"
    text.write_text("<OpenSCENARIO/>")
    with pytest.raises(SourceError, match="not a tar or zip"):
        archives.extract(text, tmp_path / "p", limits=SourceLimits())
    assert archives.sniff(b"PK\x03\x04rest") is archives.ArchiveFormat.ZIP
    assert archives.sniff(b"\x1f\x8b\x08") is archives.ArchiveFormat.TAR
    assert archives.sniff(b"<?xml") is None
