"""A hardened reader of a hand's archive: one zip or tar holding a URDF/MJCF and the mesh files it names.

An uploaded archive is untrusted input. It is read entirely in memory, never extracted to disk, and refused with a
:class:`HandLoadError` naming the member and the problem when it breaks any of these rules:

- at most ``MAX_ARCHIVE_BYTES`` compressed, ``MAX_MEMBERS`` members, ``MAX_UNPACKED_BYTES`` unpacked in all and
  ``MAX_MEMBER_BYTES`` per member, each member and the whole archive compressed at most ``MAX_RATIO`` : 1 (zip
  bombs); sizes are checked on the declared headers first and again while reading, so a lying header gains
  nothing;
- names are relative POSIX paths inside the archive: no absolute names, drive letters, backslashes, ``..``
  components, NUL or control characters, and no two members with the same normalised name;
- only regular files and folders: symbolic or hard links, devices and FIFOs are refused, not skipped;
- a binary STL whose header declares more than ``MAX_MESH_FACES`` faces is refused before it is read.

Nothing outside the archive is ever opened: the result is a name → bytes map, and every file a description names
is looked up in that map (:meth:`HandArchive.resolve`).
"""

from __future__ import annotations

import io
import posixpath
import re
import struct
import tarfile
import zipfile
from dataclasses import dataclass, field
from typing import IO

from manifoundation.core.errors import HandLoadError

MAX_ARCHIVE_BYTES = 16 * 1024 * 1024
MAX_MEMBERS = 2000
MAX_UNPACKED_BYTES = 96 * 1024 * 1024
MAX_MEMBER_BYTES = 32 * 1024 * 1024
MAX_RATIO = 200
"""Largest accepted unpacked : compressed size ratio (STL meshes deflate about 4 : 1; zip bombs reach 1000 : 1)."""
MAX_MESH_FACES = 500_000
"""Faces of one mesh file (the G1 Dex3 hand's finest mesh has 19 000)."""
MESH_SUFFIXES = (".stl", ".obj", ".dae")
DESCRIPTION_SUFFIXES = (".urdf", ".xml", ".mjcf")
_BAD_CHARS = re.compile(r"[\x00-\x1f\x7f\\]")


@dataclass
class HandArchive:
    """The members of a checked archive, name → bytes (normalised relative POSIX names, folders dropped)."""

    files: dict[str, bytes] = field(default_factory=dict)

    @property
    def unpacked_bytes(self) -> int:
        """Total size of the members."""
        return sum(len(v) for v in self.files.values())

    def descriptions(self) -> list[str]:
        """Members that may be a robot description (by suffix), shallowest first."""
        names = [n for n in self.files if n.lower().endswith(DESCRIPTION_SUFFIXES)]
        return sorted(names, key=lambda n: (n.count("/"), n))

    def resolve(self, filename: str, base: str = "") -> str:
        """The member a description's file reference names.

        ``package://pkg/a/b.stl`` is matched by the longest tail of ``pkg/a/b.stl`` that is a member (an archive
        of a package's folder keeps its tail), a bare file name only when it is unique; a relative name is taken
        against the folder ``base`` of the referring description and may not leave the archive; ``file://`` and
        absolute names are refused.

        Raises:
            HandLoadError: the reference leaves the archive or names no member.
        """
        ref = filename.strip()
        if ref.startswith("package://"):
            parts = [p for p in ref[len("package://") :].split("/") if p not in ("", ".")]
            if ".." in parts or not parts:
                raise HandLoadError(f"file {filename!r}: '..' in a package path")
            for k in range(len(parts) - 1):  # longest tail first, at least folder + file
                tail = "/".join(parts[k:])
                if tail in self.files:
                    return tail
            same = [n for n in self.files if n.rsplit("/", 1)[-1] == parts[-1]]
            if len(same) == 1:
                return same[0]
            raise HandLoadError(f"file {filename!r}: not in the archive")
        if ref.startswith("file:") or ref.startswith("/") or re.match(r"^[A-Za-z]:", ref) or "://" in ref:
            raise HandLoadError(f"file {filename!r}: absolute paths and URLs are refused (name a member)")
        path = posixpath.normpath(posixpath.join(base, ref.replace("\\", "/")))
        if path.startswith("../") or path == "..":
            raise HandLoadError(f"file {filename!r}: leaves the archive")
        if path not in self.files:
            raise HandLoadError(f"file {filename!r}: not in the archive (looked for {path!r})")
        return path


def _check_name(raw: str) -> str:
    if not raw or _BAD_CHARS.search(raw):
        raise HandLoadError(f"member {raw[:80]!r}: control characters or backslashes in the name")
    if raw.startswith("/") or re.match(r"^[A-Za-z]:", raw):
        raise HandLoadError(f"member {raw[:80]!r}: absolute name")
    parts = raw.rstrip("/").split("/")
    if ".." in parts:
        raise HandLoadError(f"member {raw[:80]!r}: path traversal ('..')")
    name = posixpath.normpath(raw)
    if name in (".", ""):
        raise HandLoadError(f"member {raw[:80]!r}: empty name")
    return name


def _check_stl_header(name: str, head: bytes, size: int) -> None:
    """Refuse a binary STL declaring too many faces (an ASCII one is bounded by the member size)."""
    if not name.lower().endswith(".stl") or len(head) < 84 or head[:5].lower() == b"solid":
        return
    (faces,) = struct.unpack("<I", head[80:84])
    if faces > MAX_MESH_FACES:
        raise HandLoadError(f"member {name!r}: mesh of {faces} faces, over the {MAX_MESH_FACES}-face limit")


class _Budget:
    """Running totals over the members, checked as each one is read."""

    def __init__(self, compressed: int) -> None:
        self.compressed = max(compressed, 1)
        self.total = 0
        self.names: set[str] = set()

    def declare(self, name: str, size: int, packed: int | None) -> None:
        if name in self.names:
            raise HandLoadError(f"member {name!r}: appears twice")
        self.names.add(name)
        if len(self.names) > MAX_MEMBERS:
            raise HandLoadError(f"more than {MAX_MEMBERS} members: refused")
        if packed is not None and size > MAX_RATIO * max(packed, 1) and size > 1024 * 1024:
            raise HandLoadError(
                f"member {name!r}: compressed {size // max(packed, 1)} : 1, a zip bomb (limit {MAX_RATIO})"
            )
        if size > MAX_MEMBER_BYTES:
            raise HandLoadError(f"member {name!r}: {size} bytes unpacked, over the {MAX_MEMBER_BYTES}-byte limit")

    def add(self, name: str, n: int) -> None:
        self.total += n
        if self.total > MAX_UNPACKED_BYTES:
            raise HandLoadError(f"archive unpacks to more than {MAX_UNPACKED_BYTES} bytes (at member {name!r})")
        if self.total > MAX_RATIO * self.compressed and self.total > 1024 * 1024:
            raise HandLoadError(f"archive compressed more than {MAX_RATIO} : 1 (at member {name!r}): a zip bomb")


def _read_limited(stream: IO[bytes], name: str, declared: int, budget: _Budget) -> bytes:
    out = bytearray()
    while chunk := stream.read(1 << 20):
        out += chunk
        budget.add(name, len(chunk))
        if len(out) > min(declared, MAX_MEMBER_BYTES):
            raise HandLoadError(f"member {name!r}: more bytes than its header declares")
        if len(out) >= 84 and len(out) - len(chunk) < 84:
            _check_stl_header(name, bytes(out[:84]), declared)
    return bytes(out)


def _read_zip(data: bytes) -> HandArchive:
    budget, files = _Budget(len(data)), {}
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as zf:
            infos = zf.infolist()
            if len(infos) > MAX_MEMBERS:
                raise HandLoadError(f"{len(infos)} members, over the {MAX_MEMBERS}-member limit")
            for info in infos:
                name = _check_name(info.filename)
                kind = (info.external_attr >> 16) & 0o170000
                if kind not in (0, 0o100000, 0o040000):  # unix mode bits: only files and folders
                    what = "a symbolic link" if kind == 0o120000 else "not a regular file"
                    raise HandLoadError(f"member {name!r}: {what}; refused")
                if info.is_dir():
                    continue
                if info.flag_bits & 0x1:
                    raise HandLoadError(f"member {name!r}: encrypted")
                if name.lower().endswith(".stl"):  # the face count first: it names the problem of a huge mesh
                    with zf.open(info) as f:
                        _check_stl_header(name, f.read(84), info.file_size)
                budget.declare(name, info.file_size, info.compress_size)
                with zf.open(info) as f:
                    files[name] = _read_limited(f, name, info.file_size, budget)
    except (zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, EOFError, OSError) as e:
        raise HandLoadError(f"malformed zip archive: {e}") from e
    return HandArchive(files)


def _read_tar(data: bytes) -> HandArchive:
    budget, files = _Budget(len(data)), {}
    try:
        with tarfile.open(fileobj=io.BytesIO(data), mode="r:*") as tf:
            count = 0
            for info in tf:  # iterated lazily: a 10 000-member tar is refused at member 2 001
                count += 1
                if count > MAX_MEMBERS:
                    raise HandLoadError(f"more than {MAX_MEMBERS} members: refused")
                name = _check_name(info.name)
                if info.issym() or info.islnk():
                    raise HandLoadError(f"member {name!r}: a {'symbolic' if info.issym() else 'hard'} link; refused")
                if info.isdir():
                    continue
                if not info.isfile():
                    raise HandLoadError(f"member {name!r}: a device, FIFO or other special file; refused")
                f = tf.extractfile(info)
                if f is None:
                    raise HandLoadError(f"member {name!r}: unreadable")
                if name.lower().endswith(".stl"):
                    _check_stl_header(name, f.read(84), info.size)
                    f.seek(0)
                budget.declare(name, info.size, None)
                files[name] = _read_limited(f, name, info.size, budget)
    except (tarfile.TarError, EOFError, OSError, ValueError) as e:  # gzip/bz2/xz errors are OSError/EOFError
        raise HandLoadError(f"malformed tar archive: {e}") from e
    return HandArchive(files)


def read_archive(data: bytes) -> HandArchive:
    """Check and read a zip or tar (optionally gzip/bz2/xz-compressed) archive in memory (see module doc).

    Args:
        data: the archive's bytes.

    Raises:
        HandLoadError: not an archive, or any rule of the module doc broken (the message names the member).
    """
    if len(data) > MAX_ARCHIVE_BYTES:
        raise HandLoadError(f"archive is {len(data)} bytes, over the {MAX_ARCHIVE_BYTES}-byte limit")
    if data[:4] == b"PK\x03\x04" or data[:4] == b"PK\x05\x06":
        return _read_zip(data)
    if data[:2] == b"\x1f\x8b" or data[:3] == b"BZh" or data[:6] == b"\xfd7zXZ\x00" or data[257:262] == b"ustar":
        return _read_tar(data)
    raise HandLoadError("archive: not a zip or tar file")
