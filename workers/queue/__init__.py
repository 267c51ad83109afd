"""Job queue backends (torch-free: the service imports this package)."""

from workers.queue.base import (
    JobNotFound,
    JobQueue,
    QueueError,
    QueueFull,
    QueueStats,
    QueueUnavailable,
    RobotInvalid,
)

__all__ = ["JobNotFound", "JobQueue", "QueueError", "QueueFull", "QueueStats", "QueueUnavailable", "RobotInvalid"]
