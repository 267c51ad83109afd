"""The part every resumable data run shares: its jobs run here or in a spawn pool, and its manifest is
rewritten atomically after each one, so a run stopped at any moment resumes from what the manifest holds."""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any, TypeVar

Job = TypeVar("Job")
Result = TypeVar("Result")


def run_jobs(fn: Callable[[Job], Result], jobs: Iterable[Job], workers: int) -> Iterator[Result]:
    """``fn`` of each job, in this process (``workers`` ≤ 1) or in ``workers`` spawned processes (results in the
    order they finish). ``fn`` must be a module-level function when ``workers`` > 1."""
    if workers <= 1:
        for job in jobs:
            yield fn(job)
        return
    import multiprocessing as mp

    with mp.get_context("spawn").Pool(workers) as pool:
        yield from pool.imap_unordered(fn, jobs)


def write_manifest(path: Path, manifest: dict[str, Any]) -> None:
    """Replace ``path`` by ``manifest`` as JSON, atomically (a reader never sees half a file)."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(manifest, indent=1))
    os.replace(tmp, path)
