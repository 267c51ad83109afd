"""The body of a hand registration from what a user has on disk: an archive, a folder, or a description file.

- a ``.zip`` / ``.tar`` / ``.tar.gz`` / ``.tgz`` / ``.tar.bz2`` / ``.tar.xz`` file (or its bytes): sent as it is;
- a folder: zipped in memory (regular files only, symbolic links skipped, hidden files skipped) — the service
  finds the description inside (its only ``.urdf``, else its top MJCF), or use ``description=``;
- a ``.urdf`` file: sent as ``urdf`` (primitives only: its mesh files are not sent), a ``.xml``/``.mjcf`` file as
  ``mjcf``; a file that names mesh files should be sent with them, as a folder or an archive.
"""

from __future__ import annotations

import io
import os
import re
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from manifoundation.contract import MAX_ARCHIVE_BYTES, RobotRegister
from manifoundation.sdk.errors import checked

ARCHIVE_SUFFIXES = (".zip", ".tar", ".tar.gz", ".tgz", ".tar.bz2", ".tbz2", ".tar.xz", ".txz")
_MAGIC = (b"PK\x03\x04", b"\x1f\x8b", b"BZh", b"\xfd7zXZ")


def zip_folder(folder: Path) -> bytes:
    """A zip of ``folder``'s regular files, paths relative to it (symbolic links and hidden files skipped).

    Raises:
        ValueError: the zip would exceed the service's archive limit.
    """
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for root, dirs, files in os.walk(folder, followlinks=False):
            dirs[:] = sorted(d for d in dirs if not d.startswith(".") and not (Path(root) / d).is_symlink())
            for name in sorted(files):
                path = Path(root) / name
                if name.startswith(".") or path.is_symlink() or not path.is_file():
                    continue
                z.write(path, path.relative_to(folder).as_posix())
    data = buf.getvalue()
    if len(data) > MAX_ARCHIVE_BYTES:
        raise ValueError(f"archive: {folder} zips to {len(data)} bytes, over the {MAX_ARCHIVE_BYTES}-byte limit")
    return data


def _clean(name: str) -> str:
    return re.sub(r"[^a-z0-9_\-]", "-", name.lower()).strip("-_")[:64] or "custom-hand"


def hand_registration(
    source: str | bytes | os.PathLike[str],
    *,
    palm: str | None = None,
    fingertips: list[str] | None = None,
    name: str | None = None,
    tip_offsets: Any = None,
    description: str | None = None,
    rest: dict[str, float] | None = None,
    approach_axis: Any = None,
) -> RobotRegister:
    """Build the body of ``POST /v1/robots`` from an archive, a folder or a description (see module doc).

    Args:
        source: a path (archive, folder, ``.urdf``, ``.xml``/``.mjcf``) or an archive's bytes.
        palm: the link the floating 6-DoF base attaches to (the sub-tree below it is the hand).
        fingertips: fingertip links (default: the sub-tree's leaf links).
        name: the name to register under (default: the file or folder name).
        tip_offsets: (len(fingertips), 3) contact points in the fingertip link frames, metres.
        description: the archive member to load (when the archive holds several descriptions).
        rest: free joint → rest value. approach_axis: (3,) palm-frame approach direction.

    Raises:
        FileNotFoundError: no such path. ValueError: an archive over the limit.
    """
    fields: dict[str, Any] = {}
    if isinstance(source, bytes):
        if not source.startswith(_MAGIC) and source[257:262] != b"ustar":
            raise ValueError("archive: bytes that are not a zip or tar; pass a path for a description file")
        fields["archive"], stem = source, "custom-hand"
    else:
        path = Path(source)
        if not path.exists():
            raise FileNotFoundError(f"no file or folder {str(path)[:80]!r}")
        stem = path.name.split(".", 1)[0]
        if path.is_dir():
            fields["archive"] = zip_folder(path)
        elif path.name.lower().endswith(ARCHIVE_SUFFIXES):
            fields["archive"] = path.read_bytes()
        elif path.suffix.lower() == ".urdf":
            fields["urdf"] = path.read_text(encoding="utf-8")
        else:
            fields["mjcf"] = path.read_text(encoding="utf-8")
    offsets = None if tip_offsets is None else np.asarray(tip_offsets, dtype=np.float64)
    axis = None if approach_axis is None else np.asarray(approach_axis, dtype=np.float64)
    return checked(
        RobotRegister, "", name=_clean(name or stem), palm=palm, fingertips=fingertips, tip_offsets=offsets,
        description=description, rest=rest, approach_axis=axis, **fields,
    )  # fmt: skip
