"""Per-key limits on registered robots, reserved in the store before a worker validates the registration.

The rule, the same for every front end (HTTP, gRPC, MCP) and both backends: a key holds the robots it registered
plus the registrations it has in flight (reserved, not yet answered), each name once with the larger of its sizes.
A new name is refused when the key already holds ``max_robots`` other names, and any registration when the bytes
of the key's other names plus its own pass ``max_bytes``. Registering a name again replaces it (no new slot).

The check and the reservation are one atomic step in the store (the embedded queue's lock; the ``RESERVE_ROBOT``
Lua script on Redis, which applies :func:`check`'s rule and returns the same codes), so concurrent registrations
cannot all pass a check that each made alone.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from manifoundation.contract import RobotPublic, RobotRegister
from manifoundation.server.queue.base import RobotLimitReached, RobotLimits
from manifoundation.server.queue.records import scoped_robot

COUNT, BYTES = 1, 2  # codes of a refusal (also the Lua script's)


def refusal(code: int, held: int, size: int, limits: RobotLimits) -> RobotLimitReached:
    """The error of a refusal: ``held`` is the key's other names (`COUNT`) or their bytes (`BYTES`)."""
    if code == COUNT:
        return RobotLimitReached(
            f"{held} hands registered, at most {limits.max_robots} per key (MANI_MAX_ROBOTS); "
            "DELETE /v1/robots/{name} one first"
        )
    return RobotLimitReached(
        f"archive: {size} bytes would bring this key's hands to {held + size} bytes, over {limits.max_bytes} "
        "(MANI_MAX_ROBOT_STORE_BYTES); DELETE /v1/robots/{name} one first"
    )


def check(
    registered: Mapping[str, int], pending: Iterable[tuple[str, int]], name: str, size: int, limits: RobotLimits
) -> None:
    """Apply the rule (module doc) to one key's robots.

    Args:
        registered: the key's registered robots, name → stored bytes.
        pending: the key's registrations in flight, (name, bytes) each.
        name: the robot to register.
        size: its stored bytes.
        limits: the key's limits.

    Raises:
        RobotLimitReached: the key holds ``max_robots`` other names, or the bytes would pass ``max_bytes``.
    """
    held = dict(registered)
    for other, nbytes in pending:
        held[other] = max(held.get(other, 0), nbytes)
    others = {n: b for n, b in held.items() if n != name}
    if name not in held and len(others) >= limits.max_robots:
        raise refusal(COUNT, len(others), size, limits)
    if sum(others.values()) + size > limits.max_bytes:
        raise refusal(BYTES, sum(others.values()), size, limits)


def check_in_memory(
    robots: Mapping[str, RobotPublic],
    pending: Iterable[tuple[str | None, str, int]],
    owner: str | None,
    robot: RobotRegister,
    limits: RobotLimits,
) -> None:
    """`check` on the embedded queue's store: ``robots`` by `scoped_robot` key (built-ins by name), ``pending``
    the registrations in flight as (owner, name, bytes). Raises `RobotLimitReached`."""
    registered = {
        r.name: r.stored_bytes or 0 for key, r in robots.items() if not r.builtin and key == scoped_robot(owner, r.name)
    }
    mine = [(name, size) for who, name, size in pending if who == owner]
    check(registered, mine, robot.name, robot.stored_bytes, limits)


# KEYS: robots (hash), robot sizes (hash), the owner's reservations (hash rid → "until_ms size name").
# ARGV: the owner's field prefix ("OWNER/", or "" for no owner), name, size, rid, reservation ttl (ms), max_robots,
# max_bytes. Returns {0, 0} (reserved) or {COUNT, other names} / {BYTES, their bytes}: `check`'s rule.
RESERVE_ROBOT = """
local prefix, name, size = ARGV[1], ARGV[2], tonumber(ARGV[3])
local t = redis.call('TIME')
local now = tonumber(t[1]) * 1000 + math.floor(tonumber(t[2]) / 1000)
local held = {}
for _, field in ipairs(redis.call('HKEYS', KEYS[1])) do
  local bytes = redis.call('HGET', KEYS[2], field)
  if prefix ~= '' and string.sub(field, 1, #prefix) == prefix then
    held[string.sub(field, #prefix + 1)] = tonumber(bytes or '0')
  elseif prefix == '' and bytes and not string.find(field, '/', 1, true) then
    held[field] = tonumber(bytes)
  end
end
local pending = redis.call('HGETALL', KEYS[3])
for i = 1, #pending, 2 do
  local until_ms, bytes, other = string.match(pending[i + 1], '^(%d+) (%d+) (.*)$')
  if until_ms == nil or tonumber(until_ms) < now then
    redis.call('HDEL', KEYS[3], pending[i])
  elseif (held[other] or -1) < tonumber(bytes) then
    held[other] = tonumber(bytes)
  end
end
local count, used = 0, 0
for other, bytes in pairs(held) do
  if other ~= name then count = count + 1; used = used + bytes end
end
if held[name] == nil and count >= tonumber(ARGV[6]) then return {1, count} end
if used + size > tonumber(ARGV[7]) then return {2, used} end
local ttl = tonumber(ARGV[5])
redis.call('HSET', KEYS[3], ARGV[4], (now + ttl) .. ' ' .. size .. ' ' .. name)
redis.call('PEXPIRE', KEYS[3], ttl + 1000)
return {0, 0}
"""
