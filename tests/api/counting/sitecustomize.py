"""Counts a request's and a result's encodes, decodes and validations in every process it is loaded into.

Loaded by Python at start-up (this directory first on PYTHONPATH) in `mani serve`, its embedded workers and
`mani worker`'s processes when ``MANI_TEST_COUNT_DIR`` is set; each process rewrites
``<dir>/<pid>.json`` (its role and counts) after every count, so the figures survive a process that dies by a
signal. Test-only: nothing in the product knows about it.
"""

from __future__ import annotations

import json
import os
import sys
from collections import Counter
from typing import Any

_DIR = os.environ.get("MANI_TEST_COUNT_DIR")


def _role() -> str:
    argv = " ".join(sys.orig_argv)
    for module in ("manifoundation.server.worker.child", "manifoundation.server.worker.worker"):
        if module in argv:
            return module
    return "service" if " serve" in argv else "other"


def _kind(value: Any) -> str | None:
    if isinstance(value, dict):
        if {"object", "task", "robot"} <= value.keys():
            return "request"
        if {"hand", "model_version", "proposals"} <= value.keys():
            return "result"
    return None


def install(directory: str) -> None:
    import manifoundation.contract.codec as codec
    from manifoundation.contract import SynthesisRequest, SynthesisResult

    counts: Counter[str] = Counter()
    path = os.path.join(directory, f"{os.getpid()}.json")

    def bump(key: str) -> None:
        counts[key] += 1
        tmp = f"{path}.tmp"
        with open(tmp, "w") as f:
            json.dump({"role": _role(), "counts": counts}, f)
        os.replace(tmp, path)

    pack, unpack = codec.pack, codec.unpack

    def counted_pack(value: Any) -> bytes:
        if (kind := _kind(value)) is not None:
            bump(f"encode.{kind}")
        return pack(value)

    def counted_unpack(data: bytes, *args: Any, **kwargs: Any) -> Any:
        value = unpack(data, *args, **kwargs)
        if (kind := _kind(value)) is not None:
            bump(f"decode.{kind}")
        return value

    codec.pack, codec.unpack = counted_pack, counted_unpack
    for cls, kind in ((SynthesisRequest, "request"), (SynthesisResult, "result")):
        for name in ("model_validate", "model_validate_json"):
            original = getattr(cls, name)

            def counted(*args: Any, _original: Any = original, _kind: str = kind, **kwargs: Any) -> Any:
                bump(f"validate.{_kind}")
                return _original(*args, **kwargs)

            setattr(cls, name, staticmethod(counted))
        init = cls.__init__

        def counted_init(self: Any, *args: Any, _init: Any = init, _kind: str = kind, **kwargs: Any) -> None:
            bump(f"validate.{_kind}")
            _init(self, *args, **kwargs)

        cls.__init__ = counted_init  # type: ignore[method-assign]
        original_json = cls.model_dump_json

        def counted_json(self: Any, *args: Any, _original: Any = original_json, _kind: str = kind, **kw: Any) -> str:
            bump(f"encode.{_kind}")
            return str(_original(self, *args, **kw))

        cls.model_dump_json = counted_json  # type: ignore[method-assign]


if _DIR:
    install(_DIR)
