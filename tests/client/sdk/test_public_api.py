"""The SDK's public names are exactly the documented ones, and importing it (or the CLI) stays light."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import manifoundation.sdk as sdk

ROOT = Path(__file__).resolve().parents[3]

DOCUMENTED = {
    # clients and handles
    "Client", "AsyncClient", "RetryPolicy", "Job", "AsyncJob", "Batch", "AsyncBatch",
    # inputs
    "object_from_points", "object_from_mesh", "object_from_file", "save_object", "delta_pose", "target_points",
    "force_closure", "wrench", "make_request", "robot_registration", "hand_registration", "zip_folder",
    # plans (Client.plan / submit_plan)
    "make_plan", "box_obstacle", "as_pose",
    # outputs
    "result_to_dict", "result_to_json", "load_result", "result_figure",
    # errors
    "ManiError", "RequestError", "ValidationError", "Unauthorized", "NotFound", "RateLimited", "ServerError",
    "Unreachable", "TimeoutError", "JobFailed", "JobExpired", "IncompatibleService", "MissingExtra", "NeedsHttp",
    "ContractWarning",
}  # fmt: skip


def test_all_is_exactly_the_documented_names() -> None:
    assert set(sdk.__all__) == DOCUMENTED
    assert len(sdk.__all__) == len(set(sdk.__all__))
    for name in sdk.__all__:
        assert getattr(sdk, name) is not None
        assert name in (sdk.__doc__ or ""), f"{name} is public but not in the package docstring"


def test_error_tree() -> None:
    for cls in (sdk.ValidationError, sdk.Unauthorized, sdk.NotFound, sdk.RateLimited, sdk.ServerError):
        assert issubclass(cls, sdk.RequestError)
    assert issubclass(sdk.JobExpired, sdk.JobFailed) and issubclass(sdk.JobExpired, sdk.TimeoutError)
    for cls in (sdk.RequestError, sdk.Unreachable, sdk.TimeoutError, sdk.JobFailed):
        assert issubclass(cls, sdk.ManiError)
    assert issubclass(sdk.TimeoutError, TimeoutError)  # the builtin: `except TimeoutError` catches it too


def _top_level_modules_after(code: str) -> set[str]:
    code = f"import json, sys\n{code}\nprint(json.dumps(sorted(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    return set(json.loads(out.stdout))


def _offenders(loaded: set[str], forbidden: set[str]) -> list[str]:
    return sorted(m for m in loaded if any(m == f or m.startswith(f + ".") for f in forbidden))


def test_sdk_and_cli_import_no_server_or_science_code() -> None:
    loaded = _top_level_modules_after("import manifoundation.sdk, manifoundation.cli.main")
    forbidden = {"torch", "fastapi", "manifoundation.server", "manifoundation.core", "research", "uvicorn", "plotly",
                 "trimesh", "grpc"}
    assert not _offenders(loaded, forbidden)


def test_our_cli_commands_register_without_heavy_imports() -> None:
    loaded = _top_level_modules_after(
        "import argparse\n"
        "from manifoundation.cli import batch, jobs, synthesize\n"
        "sub = argparse.ArgumentParser().add_subparsers()\n"
        "for m in (batch, jobs, synthesize): m.register(sub)\n"
    )
    forbidden = {"torch", "fastapi", "manifoundation.server", "manifoundation.core", "research", "uvicorn", "plotly",
                 "trimesh", "httpx"}
    assert not _offenders(loaded, forbidden)
