"""`mani offline`: run a directory of request files through the worker core, here or on a Ray cluster.

Requests: ``*.json`` and ``*.msgpack`` files (one `SynthesisRequest` each) and ``*.jsonl`` files (one a line).
Results: ``OUT/ID.msgpack`` (the `SynthesisResult`) or ``OUT/ID.error.json`` (its error, from the contract's
vocabulary), and ``OUT/summary.json``. A rerun skips what is finished (docs/offline.md).

Examples:
    mani offline requests/ --out results/ --workers 2
    mani offline requests/ --out results/ --ray auto --workers 16
    mani offline requests/ --out results/ --ray ray://head.example:10001 --workers 64
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2
MODELS = "manifoundation.server.worker.models_pipeline:ModelsPipeline"


def register(subparsers: Any) -> None:
    """Add ``offline`` to ``mani``."""
    p = subparsers.add_parser(
        "offline", help="run request files through the worker core (locally or on Ray), one result file each",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
    )  # fmt: skip
    p.add_argument("requests", type=Path, help="directory of *.json, *.msgpack and *.jsonl request files")
    p.add_argument("--out", type=Path, required=True, help="results directory (created; a rerun resumes in it)")
    p.add_argument("--ray", metavar="ADDRESS", default=None,
                   help="run on Ray Data at ADDRESS (auto, HOST:6379, ray://HOST:10001; local: a cluster of its own)")
    p.add_argument("--workers", type=int, default=1, help="worker processes, or Ray actors with --ray (default 1)")
    p.add_argument("--batch-size", type=int, default=8, help="requests per micro-batch of a worker (default 8)")
    p.add_argument("--window", type=int, default=10_000,
                   help="requests read into memory at a time (default 10000; each window restarts the workers)")
    p.add_argument("--pipeline", default=MODELS, help="the worker's pipeline, module:attr (default: the models)")
    p.add_argument("--pipeline-options", default="{}", help="the pipeline's keyword options, as JSON")
    p.add_argument("--weights-dir", default=None, help="network weights directory (default: the pipeline's)")
    p.add_argument("--retry-failed", action="store_true", help="run again the requests that finished with an error")
    p.add_argument("--no-progress", action="store_true")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the batch; exit 0 when every request succeeded, 1 when some failed, 2 on bad usage."""
    from manifoundation.server.offline.batch import run_batch
    from manifoundation.server.offline.synthesis import SynthesisWorker

    if not args.requests.is_dir():
        print(f"error: {args.requests} is not a directory")
        return EXIT_USAGE
    try:
        options = json.loads(args.pipeline_options)
        if not isinstance(options, dict):
            raise ValueError("not a JSON object")
        worker = SynthesisWorker(args.pipeline, options, args.weights_dir)
        summary = run_batch(args.requests, args.out, worker, ray_address=args.ray, workers=args.workers,
                            batch_size=args.batch_size, retry_failed=args.retry_failed, window=args.window,
                            progress=not args.no_progress)  # fmt: skip
    except ValueError as exc:
        print(f"error: {exc}")
        return EXIT_USAGE
    print(json.dumps({"found": summary.found, "skipped": summary.skipped, "ran": summary.ran,
                      "answered": summary.answered, "counts": summary.counts,
                      "items_per_s": round(summary.items_per_s, 2)}))  # fmt: skip
    failed = sum(n for kind, n in summary.counts.items() if kind != "succeeded")
    return EXIT_FAILED if failed else EXIT_OK


def main(argv: list[str] | None = None) -> int:
    """``python -m manifoundation.server.commands.offline REQUESTS --out OUT ...``: the command without `mani`."""
    parser = argparse.ArgumentParser(prog="mani")
    register(parser.add_subparsers())
    args = parser.parse_args(["offline", *(sys.argv[1:] if argv is None else argv)])
    return int(args.func(args))


if __name__ == "__main__":
    sys.exit(main())
