"""The hand catalogue as the API sees it: the queue's list, cached briefly, for lookups and 404s."""

from __future__ import annotations

import time

from clients.schemas import FieldError, RobotPublic, SynthesisRequest
from service.errors import NotFound
from workers.queue import JobQueue


class RobotCatalog:
    """`queue.list_robots()` cached for ``ttl`` seconds; a miss refreshes once before answering 404."""

    def __init__(self, queue: JobQueue, ttl: float) -> None:
        self.queue = queue
        self.ttl = ttl
        self._robots: list[RobotPublic] = []
        self._stamp = float("-inf")

    async def all(self, *, fresh: bool = False) -> list[RobotPublic]:
        """Every hand (built-in and registered), sorted by name."""
        if fresh or time.monotonic() - self._stamp > self.ttl:
            self._robots = sorted(await self.queue.list_robots(), key=lambda r: r.name)
            self._stamp = time.monotonic()
        return self._robots

    async def find(self, name: str) -> RobotPublic | None:
        """The hand called ``name``, or None."""
        for fresh in (False, True):
            found = next((r for r in await self.all(fresh=fresh) if r.name == name), None)
            if found is not None:
                return found
        return None

    async def get(self, name: str) -> RobotPublic:
        """The hand called ``name``. Raises `NotFound`."""
        found = await self.find(name)
        if found is None:
            raise NotFound(f"unknown hand {name!r}", detail=[FieldError(field="name", problem="unknown hand")])
        return found

    async def check(self, request: SynthesisRequest, field: str = "robot.name") -> None:
        """404 when the request names a hand nobody knows. Skipped while no worker has published its hands."""
        name = request.robot.name
        if name is None or not await self.all():
            return
        if await self.find(name) is None:
            known = ", ".join(r.name for r in self._robots)
            raise NotFound(
                f"{field}: unknown hand {name!r} (known: {known})",
                detail=[FieldError(field=field, problem=f"unknown hand {name!r}")],
            )

    def forget(self) -> None:
        """Drop the cache (after a registration)."""
        self._stamp = float("-inf")
