"""The states a job goes through and the stages of its pipeline."""

from __future__ import annotations

from enum import StrEnum


class JobState(StrEnum):
    """Where a job is in its life. Terminal: succeeded, failed, cancelled, expired."""

    QUEUED = "queued"
    RUNNING = "running"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"
    EXPIRED = "expired"

    @property
    def terminal(self) -> bool:
        """Whether the job will not change any more."""
        return self not in (JobState.QUEUED, JobState.RUNNING)


class Stage(StrEnum):
    """Pipeline stage of a running job (a plan job: repair, planning, contacts)."""

    QUEUED = "queued"
    NETWORK = "network"
    INITIALISATION = "initialisation"
    REFINEMENT = "refinement"
    VERIFICATION = "verification"
    REPAIR = "repair"
    PLANNING = "planning"
    CONTACTS = "contacts"
    DONE = "done"


class JobKind(StrEnum):
    """What a job computes: one synthesis (``POST /v1/jobs``, ``/v1/synthesize``, a batch's item) or a
    manipulation plan (``POST /v1/plans``)."""

    SYNTHESIS = "synthesis"
    PLAN = "plan"
