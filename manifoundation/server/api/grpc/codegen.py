"""Regenerate the gRPC code from `protos/` (committed; `tests/api/grpc/test_codegen.py` checks it is current).

Why committed rather than built at install time: the package installs with plain setuptools (no build hook, no
grpcio-tools on a user's machine), and a reviewer sees the generated API change in the diff. Run::

    python -m manifoundation.server.api.grpc.codegen            # rewrite the committed files in place

The proto is compiled from the repository root (``-I .``) so the generated modules import each other by their
package path (``manifoundation.contract.protos.v1``) and need no rewriting.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[4]
PROTOS = ("manifoundation/contract/protos/v1/manifoundation.proto",)
GENERATED_SUFFIXES = ("_pb2.py", "_pb2.pyi", "_pb2_grpc.py")


def generate(out: Path) -> list[Path]:
    """Compile every proto into ``out`` (Python messages, type stubs, gRPC stubs); returns the files written.

    Raises:
        RuntimeError: protoc failed (its message is printed on stderr).
    """
    import grpc_tools
    from grpc_tools import protoc

    include = str(Path(grpc_tools.__file__).parent / "_proto")
    args = ["protoc", "-I", str(ROOT), "-I", include, f"--python_out={out}", f"--pyi_out={out}",
            f"--grpc_python_out={out}", *(str(ROOT / p) for p in PROTOS)]  # fmt: skip
    if protoc.main(args) != 0:
        raise RuntimeError(f"protoc failed on {', '.join(PROTOS)}")
    return sorted(p for p in out.rglob("*") if p.name.endswith(GENERATED_SUFFIXES))


def main() -> int:
    """Regenerate in place."""
    written = generate(ROOT)
    for path in written:
        print(path.relative_to(ROOT))
    return 0


if __name__ == "__main__":
    sys.exit(main())
