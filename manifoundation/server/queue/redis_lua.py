"""Redis key layout and the Lua scripts that keep each state change atomic (shared by client and worker).

Keys under the prefix P: ``P:jobs`` (stream, one consumer group "workers"; entries ``k`` job|robot, ``id``, ``p``
msgpack payload, ``t`` the job's kind when it is not a synthesis ("plan"; also ``kind`` in its record), ``r`` the
submitting HTTP request's id when there is one, ``o`` the owner (tenant) when there is one; deleted once acked, so
XLEN = queued + running), ``P:job:ID`` (hash: the job's record, ``request_id`` and ``owner`` among its fields when
known, TTL ``record_ttl``), ``P:result:ID`` (msgpack result, TTL ``result_ttl``), ``P:recent`` (zset of ids by
submit order, ``P:seq``) and ``P:recent:OWNER`` (the same per owner), ``P:batch:ID`` (list) + ``P:batchowner:ID``,
``P:dead`` (stream of dead letters), ``P:counts`` (hash of totals), ``P:workers`` (zset by last heartbeat) +
``P:worker:ID`` (msgpack, TTL), ``P:robots`` / ``P:robot_urdf`` / ``P:robot_size`` (hashes; field = the hand's
name, ``OWNER/name`` for a tenant's registered hand; sizes in bytes, for the key's quota), ``P:robotpending:OWNER``
(hash: registrations in flight, see `manifoundation.server.queue.robot_quota`), ``P:robotreply:RID``; channel
``P:done`` announces finished job ids (and ``robot:RID``).
"""

from __future__ import annotations

GROUP = "workers"
RECENT_MAX = 10_000


class Keys:
    """Key names under one prefix."""

    def __init__(self, prefix: str) -> None:
        self.prefix = prefix
        self.stream = f"{prefix}jobs"
        self.recent = f"{prefix}recent"
        self.dead = f"{prefix}dead"
        self.counts = f"{prefix}counts"
        self.workers = f"{prefix}workers"
        self.robots = f"{prefix}robots"
        self.robot_urdf = f"{prefix}robot_urdf"
        self.robot_size = f"{prefix}robot_size"
        self.done = f"{prefix}done"

    def job(self, job_id: str) -> str:
        return f"{self.prefix}job:{job_id}"

    def result(self, job_id: str) -> str:
        return f"{self.prefix}result:{job_id}"

    def batch(self, batch_id: str) -> str:
        return f"{self.prefix}batch:{batch_id}"

    def batch_owner(self, batch_id: str) -> str:
        return f"{self.prefix}batchowner:{batch_id}"

    def recent_of(self, owner: str | None) -> str:
        return f"{self.prefix}recent:{owner}" if owner else self.recent

    def worker(self, worker_id: str) -> str:
        return f"{self.prefix}worker:{worker_id}"

    def robot_reply(self, rid: str) -> str:
        return f"{self.prefix}robotreply:{rid}"

    def robot_reservations(self, owner: str | None) -> str:
        return f"{self.prefix}robotpending:{owner or ''}"


# KEYS: stream, recent. ARGV: prefix, max_queue, record_ttl, now, n, result_ttl (ms: the submitter decides how long
# results are kept), request_id ('' = none; the same for every job of the call), owner ('' = none), then
# n × (id, payload, deadline, batch, robot, kind ('' = synthesis)). Returns n, or -(depth + 1) when the jobs do
# not fit.
SUBMIT = (
    """
local n = tonumber(ARGV[5])
local depth = redis.call('XLEN', KEYS[1])
if depth + n > tonumber(ARGV[2]) then return -(depth + 1) end
local rid = ARGV[7]
local owner = ARGV[8]
local mine = ARGV[1] .. 'recent:' .. owner
for i = 0, n - 1 do
  local b = 9 + i * 6
  local id = ARGV[b]
  local key = ARGV[1] .. 'job:' .. id
  redis.call('HSET', key, 'state', 'queued', 'created_at', ARGV[4], 'deliveries', 0, 'ttl', ARGV[6])
  if ARGV[b + 2] ~= '' then redis.call('HSET', key, 'deadline', ARGV[b + 2]) end
  if ARGV[b + 3] ~= '' then redis.call('HSET', key, 'batch_id', ARGV[b + 3]) end
  if ARGV[b + 4] ~= '' then redis.call('HSET', key, 'robot', ARGV[b + 4]) end
  local fields = {'k', 'job', 'id', id, 'p', ARGV[b + 1]}
  if rid ~= '' then
    redis.call('HSET', key, 'request_id', rid)
    table.insert(fields, 'r')
    table.insert(fields, rid)
  end
  if owner ~= '' then
    redis.call('HSET', key, 'owner', owner)
    table.insert(fields, 'o')
    table.insert(fields, owner)
  end
  if ARGV[b + 4] ~= '' then
    table.insert(fields, 'h')
    table.insert(fields, ARGV[b + 4])
  end
  if ARGV[b + 5] ~= '' then
    redis.call('HSET', key, 'kind', ARGV[b + 5])
    table.insert(fields, 't')
    table.insert(fields, ARGV[b + 5])
  end
  local entry = redis.call('XADD', KEYS[1], '*', unpack(fields))
  redis.call('HSET', key, 'entry', entry)
  redis.call('EXPIRE', key, ARGV[3])
  local seq = redis.call('INCR', ARGV[1] .. 'seq')
  redis.call('ZADD', KEYS[2], seq, id)
  if owner ~= '' then redis.call('ZADD', mine, seq, id) end
end
redis.call('ZREMRANGEBYRANK', KEYS[2], 0, -("""
    + str(RECENT_MAX)
    + """ + 1))
if owner ~= '' then
  redis.call('ZREMRANGEBYRANK', mine, 0, -("""
    + str(RECENT_MAX)
    + """ + 1))
  redis.call('EXPIRE', mine, ARGV[3])
end
return n
"""
)

# A worker takes a delivered job. KEYS: job. ARGV: worker, now, max_deliveries.
# Returns {verdict, deliveries, created_at, deadline (run only)}; verdict: run | dead | expired | cancelled | skip.
# A job found "running" was being run by a worker that stopped responding: that becomes its last error.
BEGIN = """
local st = redis.call('HGET', KEYS[1], 'state')
if not st or (st ~= 'queued' and st ~= 'running') then return {'skip', 0} end
if st == 'running' then
  local prev = redis.call('HGET', KEYS[1], 'worker') or '?'
  local d = redis.call('HGET', KEYS[1], 'deliveries') or '0'
  redis.call('HSET', KEYS[1], 'error_type', 'WorkerLost', 'error',
    'worker ' .. prev .. ' stopped responding while running the job (delivery ' .. d .. ' of ' .. ARGV[3] .. ')')
end
if redis.call('HGET', KEYS[1], 'cancel') == '1' then return {'cancelled', 0} end
local d = redis.call('HINCRBY', KEYS[1], 'deliveries', 1)
if d > tonumber(ARGV[3]) then
  redis.call('HSET', KEYS[1], 'deliveries', d - 1)
  return {'dead', d - 1}
end
local deadline = redis.call('HGET', KEYS[1], 'deadline')
if deadline and tonumber(deadline) <= tonumber(ARGV[2]) then return {'expired', d} end
redis.call('HSET', KEYS[1], 'state', 'running', 'worker', ARGV[1], 'started_at', ARGV[2], 'progress', '')
return {'run', d, redis.call('HGET', KEYS[1], 'created_at'), deadline or ''}
"""

# Finish a job, but only if this worker still owns its stream entry (so a job re-delivered elsewhere yields one
# result). The result is written before the XACK, in the same atomic step.
# KEYS: stream, job, result, counts, done-channel.
# ARGV: group, worker, entry, state, now, result ('' = none), error, error_type, timings, progress, result_ttl
#       (used when the record does not carry the submitter's),
#       record_ttl, job id, require_owner ('1'/'0'), error detail (msgpack list of {field, problem}; '' = none).
FINISH = """
if ARGV[14] == '1' then
  local p = redis.call('XPENDING', KEYS[1], ARGV[1], ARGV[3], ARGV[3], 1)
  if (not p[1]) or p[1][2] ~= ARGV[2] then return 0 end
end
local st = redis.call('HGET', KEYS[2], 'state')
if st == 'queued' or st == 'running' then
  local ttl = redis.call('HGET', KEYS[2], 'ttl') or ARGV[11]
  if ARGV[6] ~= '' then redis.call('SET', KEYS[3], ARGV[6], 'PX', ttl) end
  redis.call('HSET', KEYS[2], 'state', ARGV[4], 'finished_at', ARGV[5], 'timings', ARGV[9], 'progress', ARGV[10])
  if ARGV[7] ~= '' then redis.call('HSET', KEYS[2], 'error', ARGV[7], 'error_type', ARGV[8]) end
  if ARGV[15] and ARGV[15] ~= '' then redis.call('HSET', KEYS[2], 'error_detail', ARGV[15]) end
  redis.call('PEXPIRE', KEYS[2], math.max(tonumber(ARGV[12]), tonumber(ttl)))
  redis.call('HINCRBY', KEYS[4], ARGV[4], 1)
end
if ARGV[3] ~= '' then
  redis.call('XACK', KEYS[1], ARGV[1], ARGV[3])
  redis.call('XDEL', KEYS[1], ARGV[3])
end
redis.call('PUBLISH', KEYS[5], ARGV[13])
return 1
"""

# Cancel (or expire) on the client side. KEYS: stream, job, counts, done-channel.
# ARGV: group, now, state (cancelled|expired), error, error_type, job id, record_ttl.
# A queued job ends at once (its entry acked and deleted); a running one is flagged for its worker.
CANCEL = """
local st = redis.call('HGET', KEYS[2], 'state')
if not st then return 'missing' end
if st == 'queued' then
  redis.call('HSET', KEYS[2], 'state', ARGV[3], 'finished_at', ARGV[2], 'error', ARGV[4], 'error_type', ARGV[5])
  local entry = redis.call('HGET', KEYS[2], 'entry')
  if entry then
    redis.call('XACK', KEYS[1], ARGV[1], entry)
    redis.call('XDEL', KEYS[1], entry)
  end
  redis.call('PEXPIRE', KEYS[2], ARGV[7])
  redis.call('HINCRBY', KEYS[3], ARGV[3], 1)
  redis.call('PUBLISH', KEYS[4], ARGV[6])
  return ARGV[3]
end
if st == 'running' and ARGV[3] == 'cancelled' then redis.call('HSET', KEYS[2], 'cancel', '1') end
return st
"""

# Heartbeat: reset the idle time of the entries this worker still owns, so a long job is not re-delivered.
# KEYS: stream. ARGV: group, worker, entry ids...
TOUCH = """
local n = 0
for i = 3, #ARGV do
  local p = redis.call('XPENDING', KEYS[1], ARGV[1], ARGV[i], ARGV[i], 1)
  if p[1] and p[1][2] == ARGV[2] then
    redis.call('XCLAIM', KEYS[1], ARGV[1], ARGV[2], 0, ARGV[i], 'JUSTID')
    n = n + 1
  end
end
return n
"""
