"""The committed generated code is what `grpcio-tools` makes of the committed proto today."""

from __future__ import annotations

from pathlib import Path

from manifoundation.server.api.grpc import codegen


def test_generated_code_is_current(tmp_path: Path) -> None:
    written = codegen.generate(tmp_path)
    assert {p.name for p in written} == {
        "manifoundation_pb2.py", "manifoundation_pb2.pyi", "manifoundation_pb2_grpc.py",
    }  # fmt: skip
    for path in written:
        committed = codegen.ROOT / path.relative_to(tmp_path)
        assert committed.read_text() == path.read_text(), (
            f"{committed.relative_to(codegen.ROOT)} is stale: run `python -m manifoundation.server.api.grpc.codegen`"
        )
