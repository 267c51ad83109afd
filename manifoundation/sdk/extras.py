"""The optional parts of the client distribution (its extras) and a clear error when one is not installed.

``pip install manifoundation-client`` brings the HTTP SDK and the CLI; the extras add the gRPC client
(``[grpc]``), the offline 3D view (``[view]``: plotly) and mesh files as objects (``[mesh]``: trimesh). The full
``manifoundation`` install has all of them.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from manifoundation.sdk.errors import MissingExtra


def missing_extra(exc: ModuleNotFoundError, extra: str, purpose: str) -> MissingExtra:
    """The SDK's error for ``exc`` (an import of an extra's package that failed), naming the extra to install."""
    return MissingExtra(
        f"{purpose} needs the package {exc.name!r}, which is not installed: "
        f"pip install 'manifoundation-client[{extra}]'",
        extra=extra,
    )


def require(module: str, extra: str, purpose: str) -> ModuleType:
    """Import ``module`` from the ``extra`` (e.g. ``require("plotly.graph_objects", "view", "result_figure")``).

    Raises:
        MissingExtra: the extra is not installed (any other import error is raised as it is).
    """
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as exc:
        if exc.name != module.partition(".")[0]:  # the package is there, but broken: not a missing extra
            raise
        raise missing_extra(exc, extra, purpose) from exc
