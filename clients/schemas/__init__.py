"""Wire contract v1, shared by the service, the workers and the SDK (pydantic v2 only).

Conventions: metres, seconds, newtons; right-handed frames; quaternions (w, x, y, z); outward unit normals;
arrays as nested lists in JSON and typed binary in msgpack (`clients.arrays`). Schemas are named by role:
``...In`` (part of a request), ``...Create`` / ``...Register`` (a POST body), ``...Public`` (what we answer).
"""

from clients.schemas.common import MAX_POINTS, MIN_POINTS, SCHEMA_VERSION, WireModel
from clients.schemas.errors import ErrorBody, ErrorType, FieldError
from clients.schemas.jobs import (
    MAX_BATCH_SIZE,
    BatchCreate,
    BatchItem,
    BatchPublic,
    DeadLetter,
    JobCreated,
    JobProgress,
    JobPublic,
    ReadyPublic,
    WorkerPublic,
)
from clients.schemas.objects import (
    MATERIAL_PROPERTIES,
    PROPERTY_NAMES,
    ArticulationJoint,
    Material,
    MeshIn,
    ObjectIn,
    PhysicalProperties,
)
from clients.schemas.requests import ContactsIn, Method, SynthesisOptions, SynthesisRequest
from clients.schemas.results import HandMesh, IterationRecord, Proposal, Quality, SynthesisResult
from clients.schemas.robots import MAX_ARCHIVE_BYTES, MAX_URDF_BYTES, RobotIn, RobotPreview, RobotPublic, RobotRegister
from clients.schemas.service import (
    DashboardPublic,
    HealthPublic,
    JobList,
    QueueStats,
    RobotList,
    Sample,
    ScenePublic,
)
from clients.schemas.states import JobState, Stage
from clients.schemas.tasks import (
    DeltaPoseTask,
    ForceClosureTask,
    JointMotionTask,
    PointMotionTask,
    TargetPointsTask,
    TaskIn,
    WrenchTask,
)

__all__ = [
    "MATERIAL_PROPERTIES",
    "MAX_ARCHIVE_BYTES",
    "MAX_BATCH_SIZE",
    "MAX_POINTS",
    "MAX_URDF_BYTES",
    "MIN_POINTS",
    "PROPERTY_NAMES",
    "SCHEMA_VERSION",
    "ArticulationJoint",
    "BatchCreate",
    "BatchItem",
    "BatchPublic",
    "ContactsIn",
    "DashboardPublic",
    "DeadLetter",
    "DeltaPoseTask",
    "ErrorBody",
    "ErrorType",
    "FieldError",
    "ForceClosureTask",
    "HandMesh",
    "HealthPublic",
    "IterationRecord",
    "JobCreated",
    "JobList",
    "JobProgress",
    "JobPublic",
    "JobState",
    "JointMotionTask",
    "Material",
    "MeshIn",
    "Method",
    "ObjectIn",
    "PhysicalProperties",
    "PointMotionTask",
    "Proposal",
    "Quality",
    "QueueStats",
    "ReadyPublic",
    "RobotIn",
    "RobotList",
    "RobotPreview",
    "RobotPublic",
    "RobotRegister",
    "Sample",
    "ScenePublic",
    "Stage",
    "SynthesisOptions",
    "SynthesisRequest",
    "SynthesisResult",
    "TargetPointsTask",
    "TaskIn",
    "WireModel",
    "WorkerPublic",
    "WrenchTask",
]
