"""Request files → items: one request per ``*.json`` / ``*.msgpack`` file, one per line of a ``*.jsonl`` file.

An item's id names its result file: the file's stem (``cup.json`` → ``cup``), or ``STEM-LINE`` for a JSONL line
(``many.jsonl`` line 7 → ``many-000007``). An item carries its request as the msgpack bytes the queue carries
(JSON is decoded and re-encoded here; msgpack passes as read), so the worker core's one validation applies to
files exactly as to the service's jobs. A file or line that does not decode becomes an item with its error
already known (``BadRequest``): it is recorded, never skipped.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from manifoundation.contract import ErrorBody, ErrorType
from manifoundation.contract.codec import DecodeError, decode_body, pack

SUFFIXES = (".json", ".msgpack", ".jsonl")


@dataclass(frozen=True)
class Item:
    """One request of a batch: its bytes (msgpack) to run, or the error that stopped it from being read."""

    id: str
    request: bytes = b""
    error: ErrorBody | None = None


@dataclass(frozen=True)
class ItemRef:
    """Where an item's request lies: a whole file, or ``length`` bytes at ``offset`` (a JSONL line). A batch holds
    these for all its requests and the requests themselves for one window at a time."""

    id: str
    path: Path
    offset: int = 0
    length: int = -1  # -1: the whole file
    where: str = ""  # how messages name it (``many.jsonl line 7``)


def list_items(directory: Path) -> list[ItemRef]:
    """Every request under ``directory`` (not recursive), in file-name order, unread.

    Raises:
        ValueError: two files give the same item id (``a.json`` and ``a.msgpack``).
    """
    refs: list[ItemRef] = []
    for path in sorted(p for p in directory.iterdir() if p.is_file() and p.suffix in SUFFIXES):
        refs.extend(_lines(path) if path.suffix == ".jsonl" else [ItemRef(path.stem, path, where=path.name)])
    seen: set[str] = set()
    for ref in refs:
        if ref.id in seen:
            raise ValueError(f"{directory}: two requests are named {ref.id!r}; rename one of their files")
        seen.add(ref.id)
    return refs


def load(ref: ItemRef) -> Item:
    """The item ``ref`` points at, its request as msgpack bytes (or its ``BadRequest`` error)."""
    with ref.path.open("rb") as f:
        f.seek(ref.offset)
        data = f.read(ref.length)
    if ref.path.suffix == ".msgpack":
        return Item(ref.id, request=data)
    try:
        return Item(ref.id, request=pack(decode_body(data, "application/json")))
    except (DecodeError, TypeError, ValueError) as exc:
        return Item(ref.id, error=ErrorBody.of(ErrorType.BAD_REQUEST, f"{ref.where}: {exc}"[:2000]))


def read_items(directory: Path) -> list[Item]:
    """Every request under ``directory``, read (`list_items` + `load`)."""
    return [load(ref) for ref in list_items(directory)]


def _lines(path: Path) -> list[ItemRef]:
    refs, offset = [], 0
    with path.open("rb") as f:
        for n, line in enumerate(f, start=1):
            if line.strip():
                refs.append(ItemRef(f"{path.stem}-{n:06d}", path, offset, len(line), f"{path.name} line {n}"))
            offset += len(line)
    return refs
