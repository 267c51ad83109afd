"""`mani jobs`: list recent jobs, show one (with its result), cancel one.

``show`` and ``cancel`` take ``--grpc HOST:PORT`` as well (`common.job_client`); ``list`` is HTTP only (the gRPC
contract has no call listing jobs).
"""

from __future__ import annotations

import argparse
from datetime import datetime
from pathlib import Path
from typing import Any

from manifoundation.cli import common


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``mani jobs`` with ``list`` (default), ``show`` and ``cancel``."""
    parser = common.command_parser(
        subparsers,
        "jobs",
        "List recent jobs (default), show one, or cancel one.",
        "mani jobs --limit 20   |   mani jobs show JOB_ID --out result.json   |   mani jobs cancel JOB_ID",
        run_list,
    )
    _list_args(parser)
    common.add_connection_args(parser)
    actions = parser.add_subparsers(dest="jobs_command", metavar="ACTION")

    listing = common.command_parser(
        actions, "list", "List recent jobs, newest first.", "mani jobs list --limit 20", run_list
    )
    _list_args(listing)
    common.add_connection_args(listing)

    show = common.command_parser(
        actions,
        "show",
        "Show one job: state, stage, timings, and its result or error; --follow waits for it with a progress bar.",
        "mani jobs show JOB_ID --follow --out result.json   (over gRPC: add --grpc 127.0.0.1:50051)",
        run_show,
    )
    show.add_argument("job_id", metavar="JOB_ID")
    show.add_argument("--follow", action="store_true", help="wait for the job to end, showing its progress")
    show.add_argument("--timeout", type=float, default=600.0, help="with --follow: seconds to wait (default 600)")
    show.add_argument("--out", type=Path, help="write the result as JSON to this file")
    common.add_connection_args(show, grpc=True)

    cancel = common.command_parser(
        actions, "cancel", "Cancel a queued or running job.", "mani jobs cancel JOB_ID", run_cancel
    )
    cancel.add_argument("job_id", metavar="JOB_ID")
    common.add_connection_args(cancel, grpc=True)


def _list_args(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--limit", type=int, default=20, help="how many jobs (default 20)")
    parser.add_argument("--state", help="only jobs in this state (queued, running, succeeded, failed, ...)")


def _when(ts: float | None) -> str:
    return "-" if ts is None else datetime.fromtimestamp(ts).strftime("%H:%M:%S")


def job_summary(job: Any) -> dict[str, Any]:
    """A job as plain data, without its (large) result."""
    data: dict[str, Any] = job.model_dump(mode="json", exclude_none=True, exclude={"result"})
    if job.result is not None:
        best = job.result.best
        data["result_summary"] = {
            "hand": job.result.hand,
            "proposals": len(job.result.proposals),
            "success": bool(best and best.quality.success),
        }
    return data


@common.run_guarded
def run_list(args: argparse.Namespace) -> int:
    """Run ``mani jobs [list]``."""
    with common.client_factory(args) as client:
        jobs = client.jobs(limit=args.limit)
    if args.state:
        jobs = [j for j in jobs if j.state.value == args.state]
    if args.json:
        common.print_json([job_summary(j) for j in jobs])
        return common.EXIT_OK
    from rich.table import Table

    table = Table(title=f"recent jobs ({len(jobs)})")
    width = max((len(j.id) for j in jobs), default=8)
    table.add_column("id", no_wrap=True, min_width=width)
    table.add_column("state", no_wrap=True, min_width=9)
    for column in ("stage", "created", "finished", "worker", "batch", "error"):
        table.add_column(column, overflow="ellipsis")
    colours = {"succeeded": "green", "failed": "red", "running": "cyan", "cancelled": "yellow", "expired": "yellow"}
    for j in jobs:
        state = f"[{colours.get(j.state.value, 'white')}]{j.state.value}[/]"
        error = j.error.type if j.error else ""
        table.add_row(
            j.id,
            state,
            j.progress.stage.value,
            _when(j.created_at),
            _when(j.finished_at),
            j.worker or "",
            j.batch_id or "",
            error,
        )
    common.stdout_console().print(table)
    return common.EXIT_OK


@common.run_guarded
def run_show(args: argparse.Namespace) -> int:
    """Run ``mani jobs show``."""
    from manifoundation.cli.synthesize import result_table, wait_with_progress
    from manifoundation.sdk import result_to_json

    with common.job_client(args) as client:
        job = client.job(args.job_id)
        status = wait_with_progress(job, args.timeout, show=not args.json) if args.follow else job.status()
        if args.follow and status.result is None and status.error is None:
            status = job.status()
    if args.out is not None and status.result is not None:
        result_to_json(status.result, args.out)
    if args.json:
        data = job_summary(status)
        if status.result is not None:
            data["result"] = status.result.model_dump(mode="json", exclude_none=True)
        common.print_json(data)
    else:
        console = common.stdout_console()
        progress = status.progress
        line = f"job {status.id}: {status.state.value}, stage {progress.stage.value} ({progress.fraction:.0%})"
        console.print(line)
        if status.timings:
            console.print("timings: " + ", ".join(f"{k} {v:.3f} s" for k, v in status.timings.items()))
        if status.error is not None:
            console.print(f"[red]{status.error.type}[/]: {status.error.error}")
        if status.result is not None:
            console.print(result_table(status.result))
        if args.out is not None and status.result is not None:
            console.print(f"result written to {args.out}")
    ok = status.state.value == "succeeded" or not status.state.terminal
    return common.EXIT_OK if ok else common.EXIT_FAILED


@common.run_guarded
def run_cancel(args: argparse.Namespace) -> int:
    """Run ``mani jobs cancel``."""
    with common.job_client(args) as client:
        status = client.job(args.job_id).cancel()
    if args.json:
        common.print_json(job_summary(status))
    else:
        print(f"job {status.id}: {status.state.value}")
    return common.EXIT_OK
