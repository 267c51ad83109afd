"""The hand catalogue as the API sees it: the queue's list per tenant, cached briefly, for lookups and 404s."""

from __future__ import annotations

import time

from manifoundation.contract import FieldError, JobRequest, RobotPublic, RobotRegister
from manifoundation.server.api.errors import Conflict, UnknownHand
from manifoundation.server.queue import JobQueue, RobotLimits
from manifoundation.server.spool import SpooledRequest, robot_of


class RobotCatalog:
    """`queue.list_robots(owner=...)` cached for ``ttl`` seconds per owner; a miss refreshes once before 404."""

    def __init__(self, queue: JobQueue, ttl: float) -> None:
        self.queue = queue
        self.ttl = ttl
        self._robots: dict[str | None, tuple[float, list[RobotPublic]]] = {}

    async def all(self, owner: str | None = None, *, fresh: bool = False) -> list[RobotPublic]:
        """Every hand ``owner`` may use (built-in and its registered ones), sorted by name."""
        stamp, robots = self._robots.get(owner, (float("-inf"), []))
        if fresh or time.monotonic() - stamp > self.ttl:
            robots = sorted(await self.queue.list_robots(owner=owner), key=lambda r: r.name)
            self._robots[owner] = (time.monotonic(), robots)
            while len(self._robots) > 10_000:  # bounded: one entry per tenant seen recently
                self._robots.pop(next(iter(self._robots)))
        return robots

    async def find(self, name: str, owner: str | None = None) -> RobotPublic | None:
        """The hand called ``name`` that ``owner`` may use, or None."""
        for fresh in (False, True):
            found = next((r for r in await self.all(owner, fresh=fresh) if r.name == name), None)
            if found is not None:
                return found
        return None

    async def get(self, name: str, owner: str | None = None) -> RobotPublic:
        """The hand called ``name``. Raises `UnknownHand` (404)."""
        found = await self.find(name, owner)
        if found is None:
            raise UnknownHand(f"unknown hand {name!r}", detail=[FieldError(field="name", problem="unknown hand")])
        return found

    async def check(
        self, request: JobRequest | SpooledRequest, owner: str | None = None, field: str = "robot.name"
    ) -> None:
        """404 when the request names a hand ``owner`` cannot use. Skipped while no worker has published hands."""
        name = robot_of(request)
        if name is None or not await self.all(owner):
            return
        if await self.find(name, owner) is None:
            known = ", ".join(r.name for r in await self.all(owner))
            raise UnknownHand(
                f"{field}: unknown hand {name!r} (known: {known})",
                detail=[FieldError(field=field, problem=f"unknown hand {name!r}")],
            )

    async def register(
        self, robot: RobotRegister, owner: str | None, *, limits: RobotLimits, timeout: float
    ) -> RobotPublic:
        """Register ``robot`` for ``owner``: the one path of every front end (HTTP, gRPC, MCP).

        No built-in name; ``owner``'s count and bytes (``limits``) reserved atomically in the queue's store, so
        concurrent registrations cannot overshoot them; validated and stored by a worker.

        Raises:
            Conflict: a built-in name (409).
            RobotLimitReached: over ``limits`` (409 at every edge); `RobotInvalid`, `QueueUnavailable` as the queue.
        """
        existing = await self.find(robot.name, owner)
        if existing is not None and existing.builtin:
            raise Conflict(f"name: {robot.name!r} is a built-in hand; choose another name")
        try:
            return await self.queue.register_robot(robot, timeout=timeout, owner=owner, limits=limits)
        finally:
            self.forget(owner)

    def forget(self, owner: str | None = None) -> None:
        """Drop ``owner``'s cache (after a registration or removal)."""
        self._robots.pop(owner, None)
