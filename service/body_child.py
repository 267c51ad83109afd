"""A body-decoding process (``python -m service.body_child``): reads framed bodies on stdin, answers on stdout.

Frame in: 4-byte big-endian header length, the header (JSON: ``cls`` "module:Name", ``ct`` content type,
``size``), then ``size`` body bytes. Frame out: 8-byte big-endian length, then the pickled ``(kind, value)`` of
`service.bodies.decode`. Imports `clients` and pydantic only: no torch, no server code. Exits at EOF.
"""

from __future__ import annotations

import importlib
import json
import pickle
import sys


def main() -> None:
    from service.bodies import decode

    source, sink = sys.stdin.buffer, sys.stdout.buffer
    sys.stdout = sys.stderr  # nothing but frames ever goes to the real stdout
    while True:
        head = source.read(4)
        if len(head) < 4:
            return
        header = json.loads(source.read(int.from_bytes(head, "big")))
        data = source.read(int(header["size"]))
        module, _, name = header["cls"].partition(":")
        cls = getattr(importlib.import_module(module), name)
        try:
            blob = pickle.dumps(decode(cls, data, header["ct"]), protocol=pickle.HIGHEST_PROTOCOL)
        except Exception as exc:  # an answer that cannot be pickled is still an answer
            blob = pickle.dumps(("bad", f"body could not be read: {exc}"))
        sink.write(len(blob).to_bytes(8, "big") + blob)
        sink.flush()


if __name__ == "__main__":
    main()
