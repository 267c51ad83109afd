"""The embedded backend's registered robots: the built-in hands its workers published, and the ones each key
registered (validated by a worker, kept in this process's memory with the bytes every worker is sent).

A registration goes to the least busy worker with its deadline; no job is sent to that worker until it answers.
Still loading at the deadline, the worker answers and ends itself (`manifoundation.server.worker.overrun`), and the
pump spawns another (`EmbeddedPump._lost`, which also answers the registrations of a worker that died with them).
"""

from __future__ import annotations

import asyncio
import time
from typing import Any

from manifoundation.contract import RobotPublic, RobotRegister
from manifoundation.contract.codec import pack
from manifoundation.server.queue.base import (
    JobNotFound,
    QueueUnavailable,
    RobotDeadlineExceeded,
    RobotInvalid,
    RobotLimits,
)
from manifoundation.server.queue.embedded_parts import WorkerHandle
from manifoundation.server.queue.embedded_pump import EmbeddedPump
from manifoundation.server.queue.records import (
    NO_ANSWER,
    REGISTRATION_GRACE_S,
    new_id,
    registration_overrun,
    robot_reply,
    scoped_robot,
)
from manifoundation.server.queue.robot_quota import check_in_memory


class EmbeddedRobots(EmbeddedPump):
    """Registered robots on top of the pump (see module doc)."""

    def _reserve_robot(self, rid: str, robot: RobotRegister, owner: str | None, limits: RobotLimits | None) -> None:
        """Check ``owner``'s limits (`robot_quota.check`) on its registered robots and registrations in flight, and
        reserve this one's slot and bytes under ``rid`` (call with the lock held: check and reservation are one step).
        """
        if limits is not None:
            check_in_memory(self._robots, self._robot_reservations.values(), owner, robot, limits)
        self._robot_reservations[rid] = (owner, robot.name, robot.stored_bytes)

    def _ready(self) -> list[WorkerHandle]:
        with self._lock:
            return [w for w in self._workers.values() if w.ready]

    def _spawning(self) -> bool:
        with self._lock:
            return any(w.info is None or w.leaving for w in self._workers.values())

    async def list_robots(self, *, owner: str | None = None) -> list[RobotPublic]:
        with self._lock:
            mine = [r for key, r in self._robots.items() if r.builtin or key == scoped_robot(owner, r.name)]
        return sorted(mine, key=lambda r: (not r.builtin, r.name))

    async def register_robot(
        self, robot: RobotRegister, timeout: float = 30.0, *, owner: str | None = None,
        limits: RobotLimits | None = None,
    ) -> RobotPublic:  # fmt: skip
        deadline = time.time() + timeout
        with self._lock:
            existing = self._robots.get(robot.name)
        if existing is not None and existing.builtin:
            raise RobotInvalid(f"name: '{robot.name}' is a built-in hand")
        while not (ready := self._ready()) and self._spawning() and time.time() < deadline:
            await asyncio.sleep(0.05)  # a worker replacing one (e.g. stopped at a registration's deadline)
        if not ready:
            raise QueueUnavailable("no worker is running to validate the robot")
        worker = min(ready, key=lambda w: len(w.inflight) + len(w.registering))
        rid, loop = new_id(), asyncio.get_running_loop()
        payload = pack(robot.model_dump(mode="python", exclude_none=True))
        future: asyncio.Future[dict[str, Any]] = loop.create_future()
        with self._lock:
            self._reserve_robot(rid, robot, owner, limits)
            self._robot_replies[rid] = (loop, future)
            worker.registering[rid] = deadline  # no job is sent to it meanwhile
        try:  # at the deadline the worker answers and ends itself; the pump spawns another (`_lost`)
            worker.send({"op": "robot", "rid": rid, "deadline": deadline}, payload)
            reply = await asyncio.wait_for(future, deadline - time.time() + REGISTRATION_GRACE_S)
        except TimeoutError as exc:
            raise RobotDeadlineExceeded(registration_overrun(timeout, NO_ANSWER)) from exc
        finally:
            with self._lock:
                self._robot_replies.pop(rid, None)
                self._robot_reservations.pop(rid, None)
                worker.registering.pop(rid, None)
        public = robot_reply(reply, timeout)
        key = scoped_robot(owner, robot.name)
        with self._lock:
            self._registered[key] = payload
            self._robots[key] = public
        return public

    async def delete_robot(self, name: str, *, owner: str | None = None) -> None:
        key = scoped_robot(owner, name)
        with self._lock:
            robot = self._robots.get(key)
            if robot is None or robot.builtin:
                raise JobNotFound(f"no registered robot {name!r}")
            del self._robots[key]
            self._registered.pop(key, None)
