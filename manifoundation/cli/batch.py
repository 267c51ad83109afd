"""`mani batch submit DIR|FILE.jsonl` and `mani batch status ID`: many requests, one progress bar."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from manifoundation.cli import common

OBJECT_SUFFIXES = (".npz", ".ply", ".obj", ".stl", ".json")


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``mani batch`` with ``submit`` and ``status``."""
    from manifoundation.cli import synthesize

    parser = common.command_parser(
        subparsers,
        "batch",
        "Submit many requests at once and follow them (thousands for data generation or evaluation).",
        "mani batch submit examples/data --hand leap --method direct_grasp --wait --out results.jsonl",
    )
    actions = parser.add_subparsers(dest="batch_command", metavar="ACTION")
    parser.set_defaults(func=lambda args: _usage(parser))

    submit = common.command_parser(
        actions,
        "submit",
        "Submit every object file of a directory, or every request line of a .jsonl file, as batches of up to "
        "1000 requests.",
        "mani batch submit requests.jsonl --wait --out results.jsonl",
        run_submit,
    )
    submit.add_argument(
        "source",
        type=Path,
        metavar="DIR|FILE.jsonl",
        help="a directory of object files (.npz .ply .obj .stl, or request .json) made into requests "
        "with the options below, or a .jsonl file of SynthesisRequest lines (used as they are)",
    )
    synthesize.add_request_args(submit)
    _add_wait_args(submit)
    common.add_connection_args(submit)

    status = common.command_parser(
        actions,
        "status",
        "Show a batch's counts by state; with --wait, follow it to the end and collect its results.",
        "mani batch status b-1f2e3d --wait --out results.jsonl",
        run_status,
    )
    status.add_argument("batch_ids", nargs="+", metavar="ID", help="batch id(s) printed by `mani batch submit`")
    _add_wait_args(status)
    common.add_connection_args(status)


def _usage(parser: argparse.ArgumentParser) -> int:
    parser.print_help(sys.stderr)
    return common.EXIT_USAGE


def _add_wait_args(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("waiting")
    group.add_argument("--wait", action="store_true", help="follow the batch to the end with a progress bar")
    group.add_argument("--wait-timeout", type=float, help="give up waiting after this many seconds")
    group.add_argument("--out", type=Path, help="with --wait: write one JSON line per request, in request order")


def read_requests(source: Path, args: argparse.Namespace) -> list[Any]:
    """The requests a ``DIR`` or ``FILE.jsonl`` stands for, in a stable order."""
    import pydantic

    from manifoundation.cli.synthesize import build_request
    from manifoundation.contract import SynthesisRequest
    from manifoundation.sdk.errors import local_validation_error

    if source.is_dir():
        files = sorted(p for p in source.iterdir() if p.suffix.lower() in OBJECT_SUFFIXES)
        if not files:
            raise ValueError(f"{source}: no object files ({', '.join(OBJECT_SUFFIXES)})")
        return [build_request(args, path) for path in files]
    if source.suffix.lower() != ".jsonl":
        raise ValueError(f"{source}: give a directory or a .jsonl file of requests")
    requests = []
    for number, line in enumerate(source.read_text().splitlines(), start=1):
        if not line.strip():
            continue
        try:
            requests.append(SynthesisRequest.model_validate_json(line))
        except pydantic.ValidationError as exc:
            raise local_validation_error(exc, f"line {number}") from exc
    if not requests:
        raise ValueError(f"{source}: no requests")
    return requests


def _chunks(items: list[Any], size: int) -> Iterable[list[Any]]:
    for start in range(0, len(items), size):
        yield items[start : start + size]


@common.run_guarded
def run_submit(args: argparse.Namespace) -> int:
    """Run ``mani batch submit``."""
    from tqdm import tqdm

    from manifoundation.contract import MAX_BATCH_SIZE

    requests = read_requests(args.source, args)
    with common.client_factory(args) as client:
        batches = []
        chunks = list(_chunks(requests, MAX_BATCH_SIZE))
        for chunk in tqdm(chunks, desc="submitting", unit="batch", disable=len(chunks) < 2 or args.json):
            batches.append(client.submit_batch(chunk))
        if not args.wait:
            ids = [b.id for b in batches]
            if args.json:
                common.print_json({"batches": ids, "total": len(requests)})
            else:
                print(f"submitted {len(requests)} requests as batch(es): {' '.join(ids)}")
                print(f"follow with: mani batch status {' '.join(ids)} --wait")
            return common.EXIT_OK
        return _follow(args, batches)


@common.run_guarded
def run_status(args: argparse.Namespace) -> int:
    """Run ``mani batch status``."""
    with common.client_factory(args) as client:
        batches = [client.batch(batch_id) for batch_id in args.batch_ids]
        if args.wait:
            return _follow(args, batches)
        pages = [b.status(limit=1) for b in batches]
    if args.json:
        common.print_json(
            [
                {"id": p.id, "total": p.total, "done": p.done, "counts": {k.value: v for k, v in p.counts.items()}}
                for p in pages
            ]
        )
        return common.EXIT_OK
    from rich.table import Table

    table = Table(title="batches")
    for column in ("id", "total", "done", "counts"):
        table.add_column(column)
    for p in pages:
        counts = ", ".join(f"{k.value} {v}" for k, v in sorted(p.counts.items()))
        table.add_row(p.id, str(p.total), "yes" if p.done else "no", counts)
    common.stdout_console().print(table)
    return common.EXIT_OK


def _follow(args: argparse.Namespace, batches: list[Any]) -> int:
    """Wait for every batch with one progress bar; write --out; exit 1 when any request failed."""
    import time

    from tqdm import tqdm

    total = sum(b.total for b in batches)
    counts: dict[str, int] = {}
    out = args.out.open("w", encoding="utf-8") if args.out is not None else None
    deadline = None if args.wait_timeout is None else time.monotonic() + args.wait_timeout
    try:
        with tqdm(total=total, desc="requests", unit="req", disable=args.json, file=sys.stderr) as bar:
            offset = 0
            for batch in batches:
                left = None if deadline is None else max(0.0, deadline - time.monotonic())
                items = batch.wait(left, progress=lambda item: _advance(bar, counts, item))
                if out is not None:
                    for item in items:
                        out.write(json.dumps(_line(offset, batch.id, item)) + "\n")
                offset += len(items)
    finally:
        if out is not None:
            out.close()
    failed = total - counts.get("succeeded", 0)
    summary = {"batches": [b.id for b in batches], "total": total, "counts": counts, "failed": failed}
    if args.json:
        common.print_json(summary)
    else:
        print(f"{total} requests: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
        if args.out is not None:
            print(f"results written to {args.out}")
    return common.EXIT_FAILED if failed else common.EXIT_OK


def _advance(bar: Any, counts: dict[str, int], item: Any) -> None:
    counts[item.state.value] = counts.get(item.state.value, 0) + 1
    bar.update(1)
    bar.set_postfix({k: v for k, v in sorted(counts.items())}, refresh=False)


def _line(offset: int, batch_id: str, item: Any) -> dict[str, Any]:
    line: dict[str, Any] = {
        "index": offset + item.index,
        "batch_id": batch_id,
        "job_id": item.job_id,
        "state": item.state.value,
    }
    if item.result is not None:
        line["result"] = item.result.model_dump(mode="json", exclude_none=True)
    if item.error is not None:
        line["error"] = item.error.model_dump(mode="json", exclude_none=True)
    return line
