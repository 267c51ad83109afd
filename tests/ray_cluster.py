"""A two-node local Ray cluster for the slow offline tests: one CPU a node, bound to 127.0.0.1, shut down after."""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ray.cluster_utils import Cluster

LOOPBACK = {"RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"}
"""Ray's own switch for a loopback-only cluster: without it a driver given 127.0.0.1 dials the machine's address.
Set before ray is imported (ray reads it once), here and in the environment of a driver started as a process."""
os.environ.update(LOOPBACK)

NODE = {"num_cpus": 1, "object_store_memory": 80 * 1024**2, "node_ip_address": "127.0.0.1"}


@contextmanager
def two_nodes() -> Iterator[Cluster]:
    """A head node and a worker node with one CPU each; this process is connected to it (``ray.init``)."""
    import ray
    from ray.cluster_utils import Cluster

    cluster = Cluster(initialize_head=True, head_node_args={**NODE, "include_dashboard": False})
    try:
        cluster.add_node(**NODE)
        cluster.wait_for_nodes()
        ray.init(address=cluster.address, log_to_driver=False)
        yield cluster
    finally:
        ray.shutdown()
        cluster.shutdown()


def kill_workers(cluster: Cluster) -> list[int]:
    """SIGKILL every worker process (actors included) of the cluster's second node; returns their pids."""
    node = cluster.list_all_nodes()[1]
    raylet = node.all_processes["raylet"][0].process.pid
    killed = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
            cmdline = (stat.parent / "cmdline").read_bytes()
        except OSError:
            continue
        if int(fields[1]) == raylet and b"MapWorker" in cmdline:
            os.kill(int(stat.parent.name), signal.SIGKILL)
            killed.append(int(stat.parent.name))
    return killed


def worker_titles(cluster: Cluster) -> list[str]:
    """The command lines of the second node's worker processes (for a failing test's message)."""
    raylet = cluster.list_all_nodes()[1].all_processes["raylet"][0].process.pid
    titles = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            if int(stat.read_text().rsplit(")", 1)[1].split()[1]) == raylet:
                titles.append((stat.parent / "cmdline").read_bytes().replace(b"\0", b" ").decode()[:80])
        except OSError:
            continue
    return titles
