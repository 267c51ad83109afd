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


def read_items(directory: Path) -> list[Item]:
    """Every request under ``directory`` (not recursive), in file-name order.

    Raises:
        ValueError: two files give the same item id (``a.json`` and ``a.msgpack``).
    """
    items: list[Item] = []
    for path in sorted(p for p in directory.iterdir() if p.is_file() and p.suffix in SUFFIXES):
        items.extend(_jsonl(path) if path.suffix == ".jsonl" else [_one(path)])
    seen: set[str] = set()
    for item in items:
        if item.id in seen:
            raise ValueError(f"{directory}: two requests are named {item.id!r}; rename one of their files")
        seen.add(item.id)
    return items


def _one(path: Path) -> Item:
    data = path.read_bytes()
    if path.suffix == ".msgpack":
        return Item(path.stem, request=data)
    return _decoded(path.stem, data, path.name)


def _jsonl(path: Path) -> list[Item]:
    lines = path.read_bytes().splitlines()
    return [_decoded(f"{path.stem}-{n:06d}", line, f"{path.name} line {n}")
            for n, line in enumerate(lines, start=1) if line.strip()]  # fmt: skip


def _decoded(item_id: str, data: bytes, where: str) -> Item:
    try:
        return Item(item_id, request=pack(decode_body(data, "application/json")))
    except (DecodeError, TypeError, ValueError) as exc:
        return Item(item_id, error=ErrorBody.of(ErrorType.BAD_REQUEST, f"{where}: {exc}"[:2000]))
