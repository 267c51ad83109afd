"""A body-decoding process (``python -m manifoundation.server.api.body_child``): reads framed bodies on stdin, answers
on stdout.

Frame in: 4-byte big-endian header length, the header (JSON: ``decoder`` "module:function", ``args`` a list of
JSON values), then the body as chunks, each a 4-byte big-endian length and that many bytes, ended by a chunk of
length 0.
Frame out: 8-byte big-endian length, then the pickled ``(kind, value)`` that ``decoder(body, *args)`` answered
(`manifoundation.server.api.bodies.decode_as`, `manifoundation.server.api.mcp.uploads.stage_upload`). Decoders import
the contract, pydantic and `manifoundation.server.spool` only: no torch, no queue or worker. Exits at EOF.
"""

from __future__ import annotations

import importlib
import json
import pickle
import sys
from typing import BinaryIO


def main() -> None:
    source, sink = sys.stdin.buffer, sys.stdout.buffer
    sys.stdout = sys.stderr  # nothing but frames ever goes to the real stdout
    while True:
        head = source.read(4)
        if len(head) < 4:
            return
        header = json.loads(source.read(int.from_bytes(head, "big")))
        data = _body(source)
        module, _, name = header["decoder"].partition(":")
        decoder = getattr(importlib.import_module(module), name)
        try:
            blob = pickle.dumps(decoder(data, *header["args"]), protocol=pickle.HIGHEST_PROTOCOL)
        except Exception as exc:  # an answer that cannot be pickled is still an answer
            blob = pickle.dumps(("bad", f"body could not be read: {exc}"))
        sink.write(len(blob).to_bytes(8, "big") + blob)
        sink.flush()


def _body(source: BinaryIO) -> bytes:
    """The chunks of one body, up to the empty one, joined (the parent has already checked its size)."""
    chunks = []
    while size := int.from_bytes(source.read(4), "big"):
        chunks.append(source.read(size))
    return b"".join(chunks)


if __name__ == "__main__":
    main()
