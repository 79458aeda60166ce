"""Safe extraction of untrusted tar and zip archives (HTTP sources and git trees).

An archive from the internet (or a tree from someone's repository) must not write outside its
folder, plant links to elsewhere or fill the disk. Every member name is checked before anything is
written (no absolute paths, no ``..``, no backslashes, no devices), member count and total size
are bounded while reading (a zip's declared sizes may lie, so bytes are counted as they stream),
tar links must stay inside the folder (checked by name and again by tarfile's ``data`` filter),
zip links are refused, and a final walk confirms that every extracted path resolves inside.
"""

from __future__ import annotations

import enum
import os
import shutil
import stat
import tarfile
import zipfile
from pathlib import Path, PurePosixPath

from simtest_operator.errors import SourceError
from simtest_operator.scenarios.specs import SourceLimits

_CHUNK = 1024 * 1024


class ArchiveFormat(enum.StrEnum):
    """Archive formats a source may deliver."""

    TAR = "tar"
    """Plain or compressed (gzip, bzip2, xz) tar."""
    ZIP = "zip"


def sniff(head: bytes) -> ArchiveFormat | None:
    """The archive format of a body starting with ``head`` (>= 262 bytes), or None."""
    if head.startswith((b"PK\x03\x04", b"PK\x05\x06")):
        return ArchiveFormat.ZIP
    if head.startswith((b"\x1f\x8b", b"BZh", b"\xfd7zXZ\x00")):
        return ArchiveFormat.TAR
    if head[257:262] == b"ustar":
        return ArchiveFormat.TAR
    return None


def extract(archive: Path, dest: Path, *, limits: SourceLimits, name: str = "") -> int:
    """Extract ``archive`` into the empty or new folder ``dest``; return the number of files.

    Raises SourceError (naming ``name`` or the archive path) when the archive is unsafe, too
    large or corrupt; ``dest`` is then removed so no partial tree stays behind.
    """
    label = name or str(archive)
    with archive.open("rb") as handle:
        kind = sniff(handle.read(512))
    if kind is None:
        raise SourceError(f"{label}: not a tar or zip archive")
    dest.mkdir(parents=True, exist_ok=True)
    try:
        if kind is ArchiveFormat.ZIP:
            count = _extract_zip(archive, dest, limits=limits, label=label)
        else:
            count = _extract_tar(archive, dest, limits=limits, label=label)
        _confirm_inside(dest, label)
    except BaseException:
        shutil.rmtree(dest, ignore_errors=True)
        raise
    return count


def checked_member(name: str, label: str) -> str:
    """The normalised relative POSIX path of member ``name``; SourceError when it could escape."""
    if "\\" in name or "\x00" in name:
        raise SourceError(f"{label}: member {name!r} has a backslash or NUL in its name")
    pure = PurePosixPath(name)
    if pure.is_absolute() or (pure.parts and pure.parts[0].endswith(":")):
        raise SourceError(f"{label}: member {name!r} has an absolute path")
    if ".." in pure.parts:
        raise SourceError(f"{label}: member {name!r} points outside the archive folder ('..')")
    cleaned = PurePosixPath(*[part for part in pure.parts if part not in ("", ".")])
    return cleaned.as_posix() if cleaned.parts else ""


def _extract_tar(archive: Path, dest: Path, *, limits: SourceLimits, label: str) -> int:
    try:
        with tarfile.open(archive, mode="r:*") as tar:
            members = _checked_tar_members(tar, limits=limits, label=label)
            for member in members:
                try:
                    _extract_member(tar, member, dest)
                except FILTER_ERROR as exc:
                    raise SourceError(f"{label}: unsafe member {member.name!r}: {exc}") from exc
            return sum(1 for m in members if m.isfile())
    except (tarfile.TarError, EOFError, OSError) as exc:
        raise SourceError(f"{label}: corrupt tar archive: {exc}") from exc


HAS_DATA_FILTER = hasattr(tarfile, "data_filter")
"""Python's tar extraction filters (3.12, backported to 3.11.4): Debian bookworm's 3.11.2, the
runner image's Python, has none. The members are checked before extraction either way (names,
links, types, sizes); the ``data`` filter is the second line of defence where it exists."""
FILTER_ERROR: type[Exception] = getattr(tarfile, "FilterError", tarfile.TarError)


def _extract_member(tar: tarfile.TarFile, member: tarfile.TarInfo, dest: Path) -> None:
    if HAS_DATA_FILTER:
        tar.extract(member, dest, filter="data")
    else:  # no owner, mode bits or times from the archive: nothing setuid, nothing odd
        tar.extract(member, dest, set_attrs=False)


def _checked_tar_members(
    tar: tarfile.TarFile, *, limits: SourceLimits, label: str
) -> list[tarfile.TarInfo]:
    members: list[tarfile.TarInfo] = []
    total = 0
    for member in tar:
        if len(members) >= limits.max_archive_members:
            raise SourceError(f"{label}: more than {limits.max_archive_members} archive members")
        name = checked_member(member.name, label)
        if not name:
            continue
        if member.issym() or member.islnk():
            _check_link(member, name, label)
        elif not (member.isfile() or member.isdir()):
            raise SourceError(f"{label}: member {member.name!r} is a device, FIFO or other special")
        total += member.size if member.isfile() else 0
        if total > limits.max_extracted_bytes:
            raise SourceError(
                f"{label}: extracted size exceeds the {limits.max_extracted_bytes} byte limit"
            )
        member.name = name
        members.append(member)
    return members


def _check_link(member: tarfile.TarInfo, name: str, label: str) -> None:
    target = PurePosixPath(member.linkname)
    if target.is_absolute():
        raise SourceError(f"{label}: link {member.name!r} points to the absolute path {target}")
    # Symlinks resolve relative to their own folder, hard links relative to the archive root.
    base = PurePosixPath(name).parent if member.issym() else PurePosixPath()
    depth = 0
    for part in (*base.parts, *target.parts):
        if part == "..":
            depth -= 1
        elif part not in ("", "."):
            depth += 1
        if depth < 0:
            raise SourceError(
                f"{label}: link {member.name!r} -> {member.linkname!r} escapes the archive folder"
            )


def _extract_zip(archive: Path, dest: Path, *, limits: SourceLimits, label: str) -> int:
    try:
        with zipfile.ZipFile(archive) as zipped:
            infos = zipped.infolist()
            if len(infos) > limits.max_archive_members:
                raise SourceError(
                    f"{label}: more than {limits.max_archive_members} archive members"
                )
            budget = limits.max_extracted_bytes
            files = 0
            for info in infos:
                name = checked_member(info.filename, label)
                mode = info.external_attr >> 16
                if stat.S_ISLNK(mode):
                    raise SourceError(f"{label}: member {info.filename!r} is a symbolic link")
                if info.flag_bits & 0x1:
                    raise SourceError(f"{label}: member {info.filename!r} is encrypted")
                if not name:
                    continue
                target = dest / name
                if info.is_dir():
                    target.mkdir(parents=True, exist_ok=True)
                    continue
                target.parent.mkdir(parents=True, exist_ok=True)
                budget = _copy_bounded(
                    zipped, info, target, budget=budget, limits=limits, label=label
                )
                files += 1
            return files
    except (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, OSError) as exc:
        raise SourceError(f"{label}: corrupt zip archive: {exc}") from exc


def _copy_bounded(
    zipped: zipfile.ZipFile,
    info: zipfile.ZipInfo,
    target: Path,
    *,
    budget: int,
    limits: SourceLimits,
    label: str,
) -> int:
    with zipped.open(info) as source, target.open("wb") as sink:
        while chunk := source.read(_CHUNK):
            budget -= len(chunk)
            if budget < 0:
                raise SourceError(
                    f"{label}: extracted size exceeds the {limits.max_extracted_bytes} byte limit"
                )
            sink.write(chunk)
    return budget


def _confirm_inside(dest: Path, label: str) -> None:
    root = dest.resolve()
    for folder, dirs, files in os.walk(dest):
        for entry in (*dirs, *files):
            path = Path(folder) / entry
            if not path.resolve().is_relative_to(root):
                raise SourceError(f"{label}: extracted path {entry!r} resolves outside its folder")
