from google.protobuf.internal import containers as _containers
from google.protobuf import descriptor as _descriptor
from google.protobuf import message as _message
from collections.abc import Iterable as _Iterable, Mapping as _Mapping
from typing import ClassVar as _ClassVar, Optional as _Optional, Union as _Union

DESCRIPTOR: _descriptor.FileDescriptor

class Array(_message.Message):
    __slots__ = ("dtype", "shape", "data")
    DTYPE_FIELD_NUMBER: _ClassVar[int]
    SHAPE_FIELD_NUMBER: _ClassVar[int]
    DATA_FIELD_NUMBER: _ClassVar[int]
    dtype: str
    shape: _containers.RepeatedScalarFieldContainer[int]
    data: bytes
    def __init__(self, dtype: _Optional[str] = ..., shape: _Optional[_Iterable[int]] = ..., data: _Optional[bytes] = ...) -> None: ...

class PhysicalProperties(_message.Message):
    __slots__ = ("friction", "density", "stretch", "bending", "youngs_modulus", "poisson_ratio", "yield_stress")
    FRICTION_FIELD_NUMBER: _ClassVar[int]
    DENSITY_FIELD_NUMBER: _ClassVar[int]
    STRETCH_FIELD_NUMBER: _ClassVar[int]
    BENDING_FIELD_NUMBER: _ClassVar[int]
    YOUNGS_MODULUS_FIELD_NUMBER: _ClassVar[int]
    POISSON_RATIO_FIELD_NUMBER: _ClassVar[int]
    YIELD_STRESS_FIELD_NUMBER: _ClassVar[int]
    friction: float
    density: float
    stretch: float
    bending: float
    youngs_modulus: float
    poisson_ratio: float
    yield_stress: float
    def __init__(self, friction: _Optional[float] = ..., density: _Optional[float] = ..., stretch: _Optional[float] = ..., bending: _Optional[float] = ..., youngs_modulus: _Optional[float] = ..., poisson_ratio: _Optional[float] = ..., yield_stress: _Optional[float] = ...) -> None: ...

class MeshIn(_message.Message):
    __slots__ = ("vertices", "faces")
    VERTICES_FIELD_NUMBER: _ClassVar[int]
    FACES_FIELD_NUMBER: _ClassVar[int]
    vertices: Array
    faces: Array
    def __init__(self, vertices: _Optional[_Union[Array, _Mapping]] = ..., faces: _Optional[_Union[Array, _Mapping]] = ...) -> None: ...

class ArticulationJoint(_message.Message):
    __slots__ = ("type", "axis", "origin", "part_mask")
    TYPE_FIELD_NUMBER: _ClassVar[int]
    AXIS_FIELD_NUMBER: _ClassVar[int]
    ORIGIN_FIELD_NUMBER: _ClassVar[int]
    PART_MASK_FIELD_NUMBER: _ClassVar[int]
    type: str
    axis: _containers.RepeatedScalarFieldContainer[float]
    origin: _containers.RepeatedScalarFieldContainer[float]
    part_mask: Array
    def __init__(self, type: _Optional[str] = ..., axis: _Optional[_Iterable[float]] = ..., origin: _Optional[_Iterable[float]] = ..., part_mask: _Optional[_Union[Array, _Mapping]] = ...) -> None: ...

class ObjectIn(_message.Message):
    __slots__ = ("points", "normals", "mesh", "material", "properties", "region_mask", "joint")
    POINTS_FIELD_NUMBER: _ClassVar[int]
    NORMALS_FIELD_NUMBER: _ClassVar[int]
    MESH_FIELD_NUMBER: _ClassVar[int]
    MATERIAL_FIELD_NUMBER: _ClassVar[int]
    PROPERTIES_FIELD_NUMBER: _ClassVar[int]
    REGION_MASK_FIELD_NUMBER: _ClassVar[int]
    JOINT_FIELD_NUMBER: _ClassVar[int]
    points: Array
    normals: Array
    mesh: MeshIn
    material: str
    properties: PhysicalProperties
    region_mask: Array
    joint: ArticulationJoint
    def __init__(self, points: _Optional[_Union[Array, _Mapping]] = ..., normals: _Optional[_Union[Array, _Mapping]] = ..., mesh: _Optional[_Union[MeshIn, _Mapping]] = ..., material: _Optional[str] = ..., properties: _Optional[_Union[PhysicalProperties, _Mapping]] = ..., region_mask: _Optional[_Union[Array, _Mapping]] = ..., joint: _Optional[_Union[ArticulationJoint, _Mapping]] = ...) -> None: ...

class DeltaPoseTask(_message.Message):
    __slots__ = ("translation", "rotation")
    TRANSLATION_FIELD_NUMBER: _ClassVar[int]
    ROTATION_FIELD_NUMBER: _ClassVar[int]
    translation: _containers.RepeatedScalarFieldContainer[float]
    rotation: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, translation: _Optional[_Iterable[float]] = ..., rotation: _Optional[_Iterable[float]] = ...) -> None: ...

class PointMotionTask(_message.Message):
    __slots__ = ("motion",)
    MOTION_FIELD_NUMBER: _ClassVar[int]
    motion: Array
    def __init__(self, motion: _Optional[_Union[Array, _Mapping]] = ...) -> None: ...

class TargetPointsTask(_message.Message):
    __slots__ = ("targets", "correspondence")
    TARGETS_FIELD_NUMBER: _ClassVar[int]
    CORRESPONDENCE_FIELD_NUMBER: _ClassVar[int]
    targets: Array
    correspondence: str
    def __init__(self, targets: _Optional[_Union[Array, _Mapping]] = ..., correspondence: _Optional[str] = ...) -> None: ...

class WrenchTask(_message.Message):
    __slots__ = ("wrench",)
    WRENCH_FIELD_NUMBER: _ClassVar[int]
    wrench: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, wrench: _Optional[_Iterable[float]] = ...) -> None: ...

class ForceClosureTask(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class JointMotionTask(_message.Message):
    __slots__ = ("delta",)
    DELTA_FIELD_NUMBER: _ClassVar[int]
    delta: float
    def __init__(self, delta: _Optional[float] = ...) -> None: ...

class TaskIn(_message.Message):
    __slots__ = ("delta_pose", "point_motion", "target_points", "wrench", "force_closure", "joint_motion")
    DELTA_POSE_FIELD_NUMBER: _ClassVar[int]
    POINT_MOTION_FIELD_NUMBER: _ClassVar[int]
    TARGET_POINTS_FIELD_NUMBER: _ClassVar[int]
    WRENCH_FIELD_NUMBER: _ClassVar[int]
    FORCE_CLOSURE_FIELD_NUMBER: _ClassVar[int]
    JOINT_MOTION_FIELD_NUMBER: _ClassVar[int]
    delta_pose: DeltaPoseTask
    point_motion: PointMotionTask
    target_points: TargetPointsTask
    wrench: WrenchTask
    force_closure: ForceClosureTask
    joint_motion: JointMotionTask
    def __init__(self, delta_pose: _Optional[_Union[DeltaPoseTask, _Mapping]] = ..., point_motion: _Optional[_Union[PointMotionTask, _Mapping]] = ..., target_points: _Optional[_Union[TargetPointsTask, _Mapping]] = ..., wrench: _Optional[_Union[WrenchTask, _Mapping]] = ..., force_closure: _Optional[_Union[ForceClosureTask, _Mapping]] = ..., joint_motion: _Optional[_Union[JointMotionTask, _Mapping]] = ...) -> None: ...

class RobotIn(_message.Message):
    __slots__ = ("name", "urdf", "fingertips", "tip_offsets")
    NAME_FIELD_NUMBER: _ClassVar[int]
    URDF_FIELD_NUMBER: _ClassVar[int]
    FINGERTIPS_FIELD_NUMBER: _ClassVar[int]
    TIP_OFFSETS_FIELD_NUMBER: _ClassVar[int]
    name: str
    urdf: str
    fingertips: _containers.RepeatedScalarFieldContainer[str]
    tip_offsets: Array
    def __init__(self, name: _Optional[str] = ..., urdf: _Optional[str] = ..., fingertips: _Optional[_Iterable[str]] = ..., tip_offsets: _Optional[_Union[Array, _Mapping]] = ...) -> None: ...

class SynthesisOptions(_message.Message):
    __slots__ = ("method", "num_proposals", "refine", "max_iterations", "seed", "timeout", "return_heatmap", "return_force_map", "return_history", "return_hand_mesh", "simulate_rollout", "num_contacts", "return_all_heatmaps", "stop_after_verified", "rollout_corrections", "simulate")
    METHOD_FIELD_NUMBER: _ClassVar[int]
    NUM_PROPOSALS_FIELD_NUMBER: _ClassVar[int]
    REFINE_FIELD_NUMBER: _ClassVar[int]
    MAX_ITERATIONS_FIELD_NUMBER: _ClassVar[int]
    SEED_FIELD_NUMBER: _ClassVar[int]
    TIMEOUT_FIELD_NUMBER: _ClassVar[int]
    RETURN_HEATMAP_FIELD_NUMBER: _ClassVar[int]
    RETURN_FORCE_MAP_FIELD_NUMBER: _ClassVar[int]
    RETURN_HISTORY_FIELD_NUMBER: _ClassVar[int]
    RETURN_HAND_MESH_FIELD_NUMBER: _ClassVar[int]
    SIMULATE_ROLLOUT_FIELD_NUMBER: _ClassVar[int]
    NUM_CONTACTS_FIELD_NUMBER: _ClassVar[int]
    RETURN_ALL_HEATMAPS_FIELD_NUMBER: _ClassVar[int]
    STOP_AFTER_VERIFIED_FIELD_NUMBER: _ClassVar[int]
    ROLLOUT_CORRECTIONS_FIELD_NUMBER: _ClassVar[int]
    SIMULATE_FIELD_NUMBER: _ClassVar[int]
    method: str
    num_proposals: int
    refine: bool
    max_iterations: int
    seed: int
    timeout: float
    return_heatmap: bool
    return_force_map: bool
    return_history: bool
    return_hand_mesh: bool
    simulate_rollout: bool
    num_contacts: int
    return_all_heatmaps: bool
    stop_after_verified: int
    rollout_corrections: int
    simulate: bool
    def __init__(self, method: _Optional[str] = ..., num_proposals: _Optional[int] = ..., refine: _Optional[bool] = ..., max_iterations: _Optional[int] = ..., seed: _Optional[int] = ..., timeout: _Optional[float] = ..., return_heatmap: _Optional[bool] = ..., return_force_map: _Optional[bool] = ..., return_history: _Optional[bool] = ..., return_hand_mesh: _Optional[bool] = ..., simulate_rollout: _Optional[bool] = ..., num_contacts: _Optional[int] = ..., return_all_heatmaps: _Optional[bool] = ..., stop_after_verified: _Optional[int] = ..., rollout_corrections: _Optional[int] = ..., simulate: _Optional[bool] = ...) -> None: ...

class ContactsIn(_message.Message):
    __slots__ = ("points",)
    POINTS_FIELD_NUMBER: _ClassVar[int]
    points: Array
    def __init__(self, points: _Optional[_Union[Array, _Mapping]] = ...) -> None: ...

class SynthesisRequest(_message.Message):
    __slots__ = ("object", "task", "robot", "options", "contacts")
    OBJECT_FIELD_NUMBER: _ClassVar[int]
    TASK_FIELD_NUMBER: _ClassVar[int]
    ROBOT_FIELD_NUMBER: _ClassVar[int]
    OPTIONS_FIELD_NUMBER: _ClassVar[int]
    CONTACTS_FIELD_NUMBER: _ClassVar[int]
    object: ObjectIn
    task: TaskIn
    robot: RobotIn
    options: SynthesisOptions
    contacts: ContactsIn
    def __init__(self, object: _Optional[_Union[ObjectIn, _Mapping]] = ..., task: _Optional[_Union[TaskIn, _Mapping]] = ..., robot: _Optional[_Union[RobotIn, _Mapping]] = ..., options: _Optional[_Union[SynthesisOptions, _Mapping]] = ..., contacts: _Optional[_Union[ContactsIn, _Mapping]] = ...) -> None: ...

class Quality(_message.Message):
    __slots__ = ("success", "converged", "reason", "iterations", "wrench_residual", "max_tip_distance", "penetration_depth", "self_collision_depth", "epsilon", "failures", "geometry", "physics")
    SUCCESS_FIELD_NUMBER: _ClassVar[int]
    CONVERGED_FIELD_NUMBER: _ClassVar[int]
    REASON_FIELD_NUMBER: _ClassVar[int]
    ITERATIONS_FIELD_NUMBER: _ClassVar[int]
    WRENCH_RESIDUAL_FIELD_NUMBER: _ClassVar[int]
    MAX_TIP_DISTANCE_FIELD_NUMBER: _ClassVar[int]
    PENETRATION_DEPTH_FIELD_NUMBER: _ClassVar[int]
    SELF_COLLISION_DEPTH_FIELD_NUMBER: _ClassVar[int]
    EPSILON_FIELD_NUMBER: _ClassVar[int]
    FAILURES_FIELD_NUMBER: _ClassVar[int]
    GEOMETRY_FIELD_NUMBER: _ClassVar[int]
    PHYSICS_FIELD_NUMBER: _ClassVar[int]
    success: bool
    converged: bool
    reason: str
    iterations: int
    wrench_residual: float
    max_tip_distance: float
    penetration_depth: float
    self_collision_depth: float
    epsilon: float
    failures: _containers.RepeatedScalarFieldContainer[str]
    geometry: str
    physics: PhysicsQuality
    def __init__(self, success: _Optional[bool] = ..., converged: _Optional[bool] = ..., reason: _Optional[str] = ..., iterations: _Optional[int] = ..., wrench_residual: _Optional[float] = ..., max_tip_distance: _Optional[float] = ..., penetration_depth: _Optional[float] = ..., self_collision_depth: _Optional[float] = ..., epsilon: _Optional[float] = ..., failures: _Optional[_Iterable[str]] = ..., geometry: _Optional[str] = ..., physics: _Optional[_Union[PhysicsQuality, _Mapping]] = ...) -> None: ...

class PhysicsTrial(_message.Message):
    __slots__ = ("direction", "translation", "rotation", "held")
    DIRECTION_FIELD_NUMBER: _ClassVar[int]
    TRANSLATION_FIELD_NUMBER: _ClassVar[int]
    ROTATION_FIELD_NUMBER: _ClassVar[int]
    HELD_FIELD_NUMBER: _ClassVar[int]
    direction: str
    translation: float
    rotation: float
    held: bool
    def __init__(self, direction: _Optional[str] = ..., translation: _Optional[float] = ..., rotation: _Optional[float] = ..., held: _Optional[bool] = ...) -> None: ...

class PhysicsQuality(_message.Message):
    __slots__ = ("held", "reason", "trials", "penetration", "tip_gaps", "touching_after_squeeze", "pregrasp", "squeeze", "seconds", "object_pieces", "test", "motion")
    HELD_FIELD_NUMBER: _ClassVar[int]
    REASON_FIELD_NUMBER: _ClassVar[int]
    TRIALS_FIELD_NUMBER: _ClassVar[int]
    PENETRATION_FIELD_NUMBER: _ClassVar[int]
    TIP_GAPS_FIELD_NUMBER: _ClassVar[int]
    TOUCHING_AFTER_SQUEEZE_FIELD_NUMBER: _ClassVar[int]
    PREGRASP_FIELD_NUMBER: _ClassVar[int]
    SQUEEZE_FIELD_NUMBER: _ClassVar[int]
    SECONDS_FIELD_NUMBER: _ClassVar[int]
    OBJECT_PIECES_FIELD_NUMBER: _ClassVar[int]
    TEST_FIELD_NUMBER: _ClassVar[int]
    MOTION_FIELD_NUMBER: _ClassVar[int]
    held: bool
    reason: str
    trials: _containers.RepeatedCompositeFieldContainer[PhysicsTrial]
    penetration: float
    tip_gaps: _containers.RepeatedScalarFieldContainer[float]
    touching_after_squeeze: int
    pregrasp: _containers.RepeatedScalarFieldContainer[float]
    squeeze: _containers.RepeatedScalarFieldContainer[float]
    seconds: float
    object_pieces: str
    test: str
    motion: PhysicsMotion
    def __init__(self, held: _Optional[bool] = ..., reason: _Optional[str] = ..., trials: _Optional[_Iterable[_Union[PhysicsTrial, _Mapping]]] = ..., penetration: _Optional[float] = ..., tip_gaps: _Optional[_Iterable[float]] = ..., touching_after_squeeze: _Optional[int] = ..., pregrasp: _Optional[_Iterable[float]] = ..., squeeze: _Optional[_Iterable[float]] = ..., seconds: _Optional[float] = ..., object_pieces: _Optional[str] = ..., test: _Optional[str] = ..., motion: _Optional[_Union[PhysicsMotion, _Mapping]] = ...) -> None: ...

class PhysicsMotion(_message.Message):
    __slots__ = ("translation_error", "rotation_error", "dropped", "reached")
    TRANSLATION_ERROR_FIELD_NUMBER: _ClassVar[int]
    ROTATION_ERROR_FIELD_NUMBER: _ClassVar[int]
    DROPPED_FIELD_NUMBER: _ClassVar[int]
    REACHED_FIELD_NUMBER: _ClassVar[int]
    translation_error: float
    rotation_error: float
    dropped: bool
    reached: bool
    def __init__(self, translation_error: _Optional[float] = ..., rotation_error: _Optional[float] = ..., dropped: _Optional[bool] = ..., reached: _Optional[bool] = ...) -> None: ...

class IterationRecord(_message.Message):
    __slots__ = ("residual", "tip_distance", "step")
    RESIDUAL_FIELD_NUMBER: _ClassVar[int]
    TIP_DISTANCE_FIELD_NUMBER: _ClassVar[int]
    STEP_FIELD_NUMBER: _ClassVar[int]
    residual: float
    tip_distance: float
    step: float
    def __init__(self, residual: _Optional[float] = ..., tip_distance: _Optional[float] = ..., step: _Optional[float] = ...) -> None: ...

class HandMesh(_message.Message):
    __slots__ = ("vertices", "faces")
    VERTICES_FIELD_NUMBER: _ClassVar[int]
    FACES_FIELD_NUMBER: _ClassVar[int]
    vertices: Array
    faces: Array
    def __init__(self, vertices: _Optional[_Union[Array, _Mapping]] = ..., faces: _Optional[_Union[Array, _Mapping]] = ...) -> None: ...

class Proposal(_message.Message):
    __slots__ = ("contact_points", "contact_normals", "forces", "fingertips", "palm_position", "palm_quaternion", "joint_names", "joint_values", "quality", "contact_source", "hand_spheres", "hand_mesh", "history", "contact_motions", "network_sample", "network_forces", "rollout_points", "shape_error", "contact_shift")
    CONTACT_POINTS_FIELD_NUMBER: _ClassVar[int]
    CONTACT_NORMALS_FIELD_NUMBER: _ClassVar[int]
    FORCES_FIELD_NUMBER: _ClassVar[int]
    FINGERTIPS_FIELD_NUMBER: _ClassVar[int]
    PALM_POSITION_FIELD_NUMBER: _ClassVar[int]
    PALM_QUATERNION_FIELD_NUMBER: _ClassVar[int]
    JOINT_NAMES_FIELD_NUMBER: _ClassVar[int]
    JOINT_VALUES_FIELD_NUMBER: _ClassVar[int]
    QUALITY_FIELD_NUMBER: _ClassVar[int]
    CONTACT_SOURCE_FIELD_NUMBER: _ClassVar[int]
    HAND_SPHERES_FIELD_NUMBER: _ClassVar[int]
    HAND_MESH_FIELD_NUMBER: _ClassVar[int]
    HISTORY_FIELD_NUMBER: _ClassVar[int]
    CONTACT_MOTIONS_FIELD_NUMBER: _ClassVar[int]
    NETWORK_SAMPLE_FIELD_NUMBER: _ClassVar[int]
    NETWORK_FORCES_FIELD_NUMBER: _ClassVar[int]
    ROLLOUT_POINTS_FIELD_NUMBER: _ClassVar[int]
    SHAPE_ERROR_FIELD_NUMBER: _ClassVar[int]
    CONTACT_SHIFT_FIELD_NUMBER: _ClassVar[int]
    contact_points: Array
    contact_normals: Array
    forces: Array
    fingertips: _containers.RepeatedScalarFieldContainer[str]
    palm_position: _containers.RepeatedScalarFieldContainer[float]
    palm_quaternion: _containers.RepeatedScalarFieldContainer[float]
    joint_names: _containers.RepeatedScalarFieldContainer[str]
    joint_values: _containers.RepeatedScalarFieldContainer[float]
    quality: Quality
    contact_source: str
    hand_spheres: Array
    hand_mesh: HandMesh
    history: _containers.RepeatedCompositeFieldContainer[IterationRecord]
    contact_motions: Array
    network_sample: int
    network_forces: Array
    rollout_points: Array
    shape_error: float
    contact_shift: Array
    def __init__(self, contact_points: _Optional[_Union[Array, _Mapping]] = ..., contact_normals: _Optional[_Union[Array, _Mapping]] = ..., forces: _Optional[_Union[Array, _Mapping]] = ..., fingertips: _Optional[_Iterable[str]] = ..., palm_position: _Optional[_Iterable[float]] = ..., palm_quaternion: _Optional[_Iterable[float]] = ..., joint_names: _Optional[_Iterable[str]] = ..., joint_values: _Optional[_Iterable[float]] = ..., quality: _Optional[_Union[Quality, _Mapping]] = ..., contact_source: _Optional[str] = ..., hand_spheres: _Optional[_Union[Array, _Mapping]] = ..., hand_mesh: _Optional[_Union[HandMesh, _Mapping]] = ..., history: _Optional[_Iterable[_Union[IterationRecord, _Mapping]]] = ..., contact_motions: _Optional[_Union[Array, _Mapping]] = ..., network_sample: _Optional[int] = ..., network_forces: _Optional[_Union[Array, _Mapping]] = ..., rollout_points: _Optional[_Union[Array, _Mapping]] = ..., shape_error: _Optional[float] = ..., contact_shift: _Optional[_Union[Array, _Mapping]] = ...) -> None: ...

class SynthesisResult(_message.Message):
    __slots__ = ("hand", "model_version", "proposals", "heatmap", "force_map", "timings", "heatmaps")
    class TimingsEntry(_message.Message):
        __slots__ = ("key", "value")
        KEY_FIELD_NUMBER: _ClassVar[int]
        VALUE_FIELD_NUMBER: _ClassVar[int]
        key: str
        value: float
        def __init__(self, key: _Optional[str] = ..., value: _Optional[float] = ...) -> None: ...
    HAND_FIELD_NUMBER: _ClassVar[int]
    MODEL_VERSION_FIELD_NUMBER: _ClassVar[int]
    PROPOSALS_FIELD_NUMBER: _ClassVar[int]
    HEATMAP_FIELD_NUMBER: _ClassVar[int]
    FORCE_MAP_FIELD_NUMBER: _ClassVar[int]
    TIMINGS_FIELD_NUMBER: _ClassVar[int]
    HEATMAPS_FIELD_NUMBER: _ClassVar[int]
    hand: str
    model_version: str
    proposals: _containers.RepeatedCompositeFieldContainer[Proposal]
    heatmap: Array
    force_map: Array
    timings: _containers.ScalarMap[str, float]
    heatmaps: Array
    def __init__(self, hand: _Optional[str] = ..., model_version: _Optional[str] = ..., proposals: _Optional[_Iterable[_Union[Proposal, _Mapping]]] = ..., heatmap: _Optional[_Union[Array, _Mapping]] = ..., force_map: _Optional[_Union[Array, _Mapping]] = ..., timings: _Optional[_Mapping[str, float]] = ..., heatmaps: _Optional[_Union[Array, _Mapping]] = ...) -> None: ...

class FieldError(_message.Message):
    __slots__ = ("field", "problem")
    FIELD_FIELD_NUMBER: _ClassVar[int]
    PROBLEM_FIELD_NUMBER: _ClassVar[int]
    field: str
    problem: str
    def __init__(self, field: _Optional[str] = ..., problem: _Optional[str] = ...) -> None: ...

class ErrorBody(_message.Message):
    __slots__ = ("error", "type", "detail")
    ERROR_FIELD_NUMBER: _ClassVar[int]
    TYPE_FIELD_NUMBER: _ClassVar[int]
    DETAIL_FIELD_NUMBER: _ClassVar[int]
    error: str
    type: str
    detail: _containers.RepeatedCompositeFieldContainer[FieldError]
    def __init__(self, error: _Optional[str] = ..., type: _Optional[str] = ..., detail: _Optional[_Iterable[_Union[FieldError, _Mapping]]] = ...) -> None: ...

class JobProgress(_message.Message):
    __slots__ = ("stage", "fraction", "iteration", "max_iterations", "completed", "total")
    STAGE_FIELD_NUMBER: _ClassVar[int]
    FRACTION_FIELD_NUMBER: _ClassVar[int]
    ITERATION_FIELD_NUMBER: _ClassVar[int]
    MAX_ITERATIONS_FIELD_NUMBER: _ClassVar[int]
    COMPLETED_FIELD_NUMBER: _ClassVar[int]
    TOTAL_FIELD_NUMBER: _ClassVar[int]
    stage: str
    fraction: float
    iteration: int
    max_iterations: int
    completed: int
    total: int
    def __init__(self, stage: _Optional[str] = ..., fraction: _Optional[float] = ..., iteration: _Optional[int] = ..., max_iterations: _Optional[int] = ..., completed: _Optional[int] = ..., total: _Optional[int] = ...) -> None: ...

class JobPublic(_message.Message):
    __slots__ = ("id", "kind", "state", "progress", "created_at", "started_at", "finished_at", "deadline", "deliveries", "worker", "batch_id", "timings", "result", "error", "plan")
    class TimingsEntry(_message.Message):
        __slots__ = ("key", "value")
        KEY_FIELD_NUMBER: _ClassVar[int]
        VALUE_FIELD_NUMBER: _ClassVar[int]
        key: str
        value: float
        def __init__(self, key: _Optional[str] = ..., value: _Optional[float] = ...) -> None: ...
    ID_FIELD_NUMBER: _ClassVar[int]
    KIND_FIELD_NUMBER: _ClassVar[int]
    STATE_FIELD_NUMBER: _ClassVar[int]
    PROGRESS_FIELD_NUMBER: _ClassVar[int]
    CREATED_AT_FIELD_NUMBER: _ClassVar[int]
    STARTED_AT_FIELD_NUMBER: _ClassVar[int]
    FINISHED_AT_FIELD_NUMBER: _ClassVar[int]
    DEADLINE_FIELD_NUMBER: _ClassVar[int]
    DELIVERIES_FIELD_NUMBER: _ClassVar[int]
    WORKER_FIELD_NUMBER: _ClassVar[int]
    BATCH_ID_FIELD_NUMBER: _ClassVar[int]
    TIMINGS_FIELD_NUMBER: _ClassVar[int]
    RESULT_FIELD_NUMBER: _ClassVar[int]
    ERROR_FIELD_NUMBER: _ClassVar[int]
    PLAN_FIELD_NUMBER: _ClassVar[int]
    id: str
    kind: str
    state: str
    progress: JobProgress
    created_at: float
    started_at: float
    finished_at: float
    deadline: float
    deliveries: int
    worker: str
    batch_id: str
    timings: _containers.ScalarMap[str, float]
    result: SynthesisResult
    error: ErrorBody
    plan: PlanResult
    def __init__(self, id: _Optional[str] = ..., kind: _Optional[str] = ..., state: _Optional[str] = ..., progress: _Optional[_Union[JobProgress, _Mapping]] = ..., created_at: _Optional[float] = ..., started_at: _Optional[float] = ..., finished_at: _Optional[float] = ..., deadline: _Optional[float] = ..., deliveries: _Optional[int] = ..., worker: _Optional[str] = ..., batch_id: _Optional[str] = ..., timings: _Optional[_Mapping[str, float]] = ..., result: _Optional[_Union[SynthesisResult, _Mapping]] = ..., error: _Optional[_Union[ErrorBody, _Mapping]] = ..., plan: _Optional[_Union[PlanResult, _Mapping]] = ...) -> None: ...

class JobCreated(_message.Message):
    __slots__ = ("id", "state")
    ID_FIELD_NUMBER: _ClassVar[int]
    STATE_FIELD_NUMBER: _ClassVar[int]
    id: str
    state: str
    def __init__(self, id: _Optional[str] = ..., state: _Optional[str] = ...) -> None: ...

class JobRef(_message.Message):
    __slots__ = ("id",)
    ID_FIELD_NUMBER: _ClassVar[int]
    id: str
    def __init__(self, id: _Optional[str] = ...) -> None: ...

class GetJobRequest(_message.Message):
    __slots__ = ("id", "without_result")
    ID_FIELD_NUMBER: _ClassVar[int]
    WITHOUT_RESULT_FIELD_NUMBER: _ClassVar[int]
    id: str
    without_result: bool
    def __init__(self, id: _Optional[str] = ..., without_result: _Optional[bool] = ...) -> None: ...

class WatchJobRequest(_message.Message):
    __slots__ = ("id", "cancel_on_disconnect")
    ID_FIELD_NUMBER: _ClassVar[int]
    CANCEL_ON_DISCONNECT_FIELD_NUMBER: _ClassVar[int]
    id: str
    cancel_on_disconnect: bool
    def __init__(self, id: _Optional[str] = ..., cancel_on_disconnect: _Optional[bool] = ...) -> None: ...

class MessagePiece(_message.Message):
    __slots__ = ("data",)
    DATA_FIELD_NUMBER: _ClassVar[int]
    data: bytes
    def __init__(self, data: _Optional[bytes] = ...) -> None: ...

class BatchCreate(_message.Message):
    __slots__ = ("requests",)
    REQUESTS_FIELD_NUMBER: _ClassVar[int]
    requests: _containers.RepeatedCompositeFieldContainer[SynthesisRequest]
    def __init__(self, requests: _Optional[_Iterable[_Union[SynthesisRequest, _Mapping]]] = ...) -> None: ...

class BatchItem(_message.Message):
    __slots__ = ("index", "job_id", "state", "result", "error")
    INDEX_FIELD_NUMBER: _ClassVar[int]
    JOB_ID_FIELD_NUMBER: _ClassVar[int]
    STATE_FIELD_NUMBER: _ClassVar[int]
    RESULT_FIELD_NUMBER: _ClassVar[int]
    ERROR_FIELD_NUMBER: _ClassVar[int]
    index: int
    job_id: str
    state: str
    result: SynthesisResult
    error: ErrorBody
    def __init__(self, index: _Optional[int] = ..., job_id: _Optional[str] = ..., state: _Optional[str] = ..., result: _Optional[_Union[SynthesisResult, _Mapping]] = ..., error: _Optional[_Union[ErrorBody, _Mapping]] = ...) -> None: ...

class BatchPublic(_message.Message):
    __slots__ = ("id", "total", "counts", "done", "items", "offset", "limit", "created_at")
    class CountsEntry(_message.Message):
        __slots__ = ("key", "value")
        KEY_FIELD_NUMBER: _ClassVar[int]
        VALUE_FIELD_NUMBER: _ClassVar[int]
        key: str
        value: int
        def __init__(self, key: _Optional[str] = ..., value: _Optional[int] = ...) -> None: ...
    ID_FIELD_NUMBER: _ClassVar[int]
    TOTAL_FIELD_NUMBER: _ClassVar[int]
    COUNTS_FIELD_NUMBER: _ClassVar[int]
    DONE_FIELD_NUMBER: _ClassVar[int]
    ITEMS_FIELD_NUMBER: _ClassVar[int]
    OFFSET_FIELD_NUMBER: _ClassVar[int]
    LIMIT_FIELD_NUMBER: _ClassVar[int]
    CREATED_AT_FIELD_NUMBER: _ClassVar[int]
    id: str
    total: int
    counts: _containers.ScalarMap[str, int]
    done: bool
    items: _containers.RepeatedCompositeFieldContainer[BatchItem]
    offset: int
    limit: int
    created_at: float
    def __init__(self, id: _Optional[str] = ..., total: _Optional[int] = ..., counts: _Optional[_Mapping[str, int]] = ..., done: _Optional[bool] = ..., items: _Optional[_Iterable[_Union[BatchItem, _Mapping]]] = ..., offset: _Optional[int] = ..., limit: _Optional[int] = ..., created_at: _Optional[float] = ...) -> None: ...

class GetBatchRequest(_message.Message):
    __slots__ = ("id", "offset", "limit")
    ID_FIELD_NUMBER: _ClassVar[int]
    OFFSET_FIELD_NUMBER: _ClassVar[int]
    LIMIT_FIELD_NUMBER: _ClassVar[int]
    id: str
    offset: int
    limit: int
    def __init__(self, id: _Optional[str] = ..., offset: _Optional[int] = ..., limit: _Optional[int] = ...) -> None: ...

class BatchRef(_message.Message):
    __slots__ = ("id",)
    ID_FIELD_NUMBER: _ClassVar[int]
    id: str
    def __init__(self, id: _Optional[str] = ...) -> None: ...

class PoseIn(_message.Message):
    __slots__ = ("position", "quaternion")
    POSITION_FIELD_NUMBER: _ClassVar[int]
    QUATERNION_FIELD_NUMBER: _ClassVar[int]
    position: _containers.RepeatedScalarFieldContainer[float]
    quaternion: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, position: _Optional[_Iterable[float]] = ..., quaternion: _Optional[_Iterable[float]] = ...) -> None: ...

class BoxObstacleIn(_message.Message):
    __slots__ = ("name", "size", "pose")
    NAME_FIELD_NUMBER: _ClassVar[int]
    SIZE_FIELD_NUMBER: _ClassVar[int]
    POSE_FIELD_NUMBER: _ClassVar[int]
    name: str
    size: _containers.RepeatedScalarFieldContainer[float]
    pose: PoseIn
    def __init__(self, name: _Optional[str] = ..., size: _Optional[_Iterable[float]] = ..., pose: _Optional[_Union[PoseIn, _Mapping]] = ...) -> None: ...

class MeshObstacleIn(_message.Message):
    __slots__ = ("name", "vertices", "faces", "pose")
    NAME_FIELD_NUMBER: _ClassVar[int]
    VERTICES_FIELD_NUMBER: _ClassVar[int]
    FACES_FIELD_NUMBER: _ClassVar[int]
    POSE_FIELD_NUMBER: _ClassVar[int]
    name: str
    vertices: Array
    faces: Array
    pose: PoseIn
    def __init__(self, name: _Optional[str] = ..., vertices: _Optional[_Union[Array, _Mapping]] = ..., faces: _Optional[_Union[Array, _Mapping]] = ..., pose: _Optional[_Union[PoseIn, _Mapping]] = ...) -> None: ...

class PointCloudObstacleIn(_message.Message):
    __slots__ = ("name", "points", "resolution")
    NAME_FIELD_NUMBER: _ClassVar[int]
    POINTS_FIELD_NUMBER: _ClassVar[int]
    RESOLUTION_FIELD_NUMBER: _ClassVar[int]
    name: str
    points: Array
    resolution: float
    def __init__(self, name: _Optional[str] = ..., points: _Optional[_Union[Array, _Mapping]] = ..., resolution: _Optional[float] = ...) -> None: ...

class ObstacleIn(_message.Message):
    __slots__ = ("box", "mesh", "points")
    BOX_FIELD_NUMBER: _ClassVar[int]
    MESH_FIELD_NUMBER: _ClassVar[int]
    POINTS_FIELD_NUMBER: _ClassVar[int]
    box: BoxObstacleIn
    mesh: MeshObstacleIn
    points: PointCloudObstacleIn
    def __init__(self, box: _Optional[_Union[BoxObstacleIn, _Mapping]] = ..., mesh: _Optional[_Union[MeshObstacleIn, _Mapping]] = ..., points: _Optional[_Union[PointCloudObstacleIn, _Mapping]] = ...) -> None: ...

class SupportPlaneIn(_message.Message):
    __slots__ = ("height", "tolerance")
    HEIGHT_FIELD_NUMBER: _ClassVar[int]
    TOLERANCE_FIELD_NUMBER: _ClassVar[int]
    height: float
    tolerance: float
    def __init__(self, height: _Optional[float] = ..., tolerance: _Optional[float] = ...) -> None: ...

class SceneIn(_message.Message):
    __slots__ = ("obstacles", "support_plane")
    OBSTACLES_FIELD_NUMBER: _ClassVar[int]
    SUPPORT_PLANE_FIELD_NUMBER: _ClassVar[int]
    obstacles: _containers.RepeatedCompositeFieldContainer[ObstacleIn]
    support_plane: SupportPlaneIn
    def __init__(self, obstacles: _Optional[_Iterable[_Union[ObstacleIn, _Mapping]]] = ..., support_plane: _Optional[_Union[SupportPlaneIn, _Mapping]] = ...) -> None: ...

class PlanOptions(_message.Message):
    __slots__ = ("time_limit", "translation_step", "rotation_step", "seed", "repair", "max_repair_distance", "contacts", "method", "num_proposals", "max_iterations", "max_contact_shift", "timeout", "return_hand_mesh")
    TIME_LIMIT_FIELD_NUMBER: _ClassVar[int]
    TRANSLATION_STEP_FIELD_NUMBER: _ClassVar[int]
    ROTATION_STEP_FIELD_NUMBER: _ClassVar[int]
    SEED_FIELD_NUMBER: _ClassVar[int]
    REPAIR_FIELD_NUMBER: _ClassVar[int]
    MAX_REPAIR_DISTANCE_FIELD_NUMBER: _ClassVar[int]
    CONTACTS_FIELD_NUMBER: _ClassVar[int]
    METHOD_FIELD_NUMBER: _ClassVar[int]
    NUM_PROPOSALS_FIELD_NUMBER: _ClassVar[int]
    MAX_ITERATIONS_FIELD_NUMBER: _ClassVar[int]
    MAX_CONTACT_SHIFT_FIELD_NUMBER: _ClassVar[int]
    TIMEOUT_FIELD_NUMBER: _ClassVar[int]
    RETURN_HAND_MESH_FIELD_NUMBER: _ClassVar[int]
    time_limit: float
    translation_step: float
    rotation_step: float
    seed: int
    repair: str
    max_repair_distance: float
    contacts: bool
    method: str
    num_proposals: int
    max_iterations: int
    max_contact_shift: float
    timeout: float
    return_hand_mesh: bool
    def __init__(self, time_limit: _Optional[float] = ..., translation_step: _Optional[float] = ..., rotation_step: _Optional[float] = ..., seed: _Optional[int] = ..., repair: _Optional[str] = ..., max_repair_distance: _Optional[float] = ..., contacts: _Optional[bool] = ..., method: _Optional[str] = ..., num_proposals: _Optional[int] = ..., max_iterations: _Optional[int] = ..., max_contact_shift: _Optional[float] = ..., timeout: _Optional[float] = ..., return_hand_mesh: _Optional[bool] = ...) -> None: ...

class PlanRequest(_message.Message):
    __slots__ = ("object", "start", "waypoints", "scene", "robot", "options")
    OBJECT_FIELD_NUMBER: _ClassVar[int]
    START_FIELD_NUMBER: _ClassVar[int]
    WAYPOINTS_FIELD_NUMBER: _ClassVar[int]
    SCENE_FIELD_NUMBER: _ClassVar[int]
    ROBOT_FIELD_NUMBER: _ClassVar[int]
    OPTIONS_FIELD_NUMBER: _ClassVar[int]
    object: ObjectIn
    start: PoseIn
    waypoints: _containers.RepeatedCompositeFieldContainer[PoseIn]
    scene: SceneIn
    robot: RobotIn
    options: PlanOptions
    def __init__(self, object: _Optional[_Union[ObjectIn, _Mapping]] = ..., start: _Optional[_Union[PoseIn, _Mapping]] = ..., waypoints: _Optional[_Iterable[_Union[PoseIn, _Mapping]]] = ..., scene: _Optional[_Union[SceneIn, _Mapping]] = ..., robot: _Optional[_Union[RobotIn, _Mapping]] = ..., options: _Optional[_Union[PlanOptions, _Mapping]] = ...) -> None: ...

class WaypointRepair(_message.Message):
    __slots__ = ("index", "requested", "repaired", "distance", "obstacles")
    INDEX_FIELD_NUMBER: _ClassVar[int]
    REQUESTED_FIELD_NUMBER: _ClassVar[int]
    REPAIRED_FIELD_NUMBER: _ClassVar[int]
    DISTANCE_FIELD_NUMBER: _ClassVar[int]
    OBSTACLES_FIELD_NUMBER: _ClassVar[int]
    index: int
    requested: PoseIn
    repaired: PoseIn
    distance: float
    obstacles: _containers.RepeatedScalarFieldContainer[str]
    def __init__(self, index: _Optional[int] = ..., requested: _Optional[_Union[PoseIn, _Mapping]] = ..., repaired: _Optional[_Union[PoseIn, _Mapping]] = ..., distance: _Optional[float] = ..., obstacles: _Optional[_Iterable[str]] = ...) -> None: ...

class SegmentReport(_message.Message):
    __slots__ = ("index", "straight", "planner_seconds", "simplify_seconds", "raw_states", "simplified_states", "dense_steps")
    INDEX_FIELD_NUMBER: _ClassVar[int]
    STRAIGHT_FIELD_NUMBER: _ClassVar[int]
    PLANNER_SECONDS_FIELD_NUMBER: _ClassVar[int]
    SIMPLIFY_SECONDS_FIELD_NUMBER: _ClassVar[int]
    RAW_STATES_FIELD_NUMBER: _ClassVar[int]
    SIMPLIFIED_STATES_FIELD_NUMBER: _ClassVar[int]
    DENSE_STEPS_FIELD_NUMBER: _ClassVar[int]
    index: int
    straight: bool
    planner_seconds: float
    simplify_seconds: float
    raw_states: int
    simplified_states: int
    dense_steps: int
    def __init__(self, index: _Optional[int] = ..., straight: _Optional[bool] = ..., planner_seconds: _Optional[float] = ..., simplify_seconds: _Optional[float] = ..., raw_states: _Optional[int] = ..., simplified_states: _Optional[int] = ..., dense_steps: _Optional[int] = ...) -> None: ...

class PlanStep(_message.Message):
    __slots__ = ("index", "grasp", "success", "proposal", "contact_shift", "hand_collisions", "dropped", "seconds", "calls")
    INDEX_FIELD_NUMBER: _ClassVar[int]
    GRASP_FIELD_NUMBER: _ClassVar[int]
    SUCCESS_FIELD_NUMBER: _ClassVar[int]
    PROPOSAL_FIELD_NUMBER: _ClassVar[int]
    CONTACT_SHIFT_FIELD_NUMBER: _ClassVar[int]
    HAND_COLLISIONS_FIELD_NUMBER: _ClassVar[int]
    DROPPED_FIELD_NUMBER: _ClassVar[int]
    SECONDS_FIELD_NUMBER: _ClassVar[int]
    CALLS_FIELD_NUMBER: _ClassVar[int]
    index: int
    grasp: str
    success: bool
    proposal: Proposal
    contact_shift: float
    hand_collisions: _containers.RepeatedScalarFieldContainer[str]
    dropped: str
    seconds: float
    calls: int
    def __init__(self, index: _Optional[int] = ..., grasp: _Optional[str] = ..., success: _Optional[bool] = ..., proposal: _Optional[_Union[Proposal, _Mapping]] = ..., contact_shift: _Optional[float] = ..., hand_collisions: _Optional[_Iterable[str]] = ..., dropped: _Optional[str] = ..., seconds: _Optional[float] = ..., calls: _Optional[int] = ...) -> None: ...

class PlanResult(_message.Message):
    __slots__ = ("success", "positions", "quaternions", "waypoint_indices", "repairs", "segments", "steps", "regrasps", "kept_share", "hand", "model_version", "timings")
    class TimingsEntry(_message.Message):
        __slots__ = ("key", "value")
        KEY_FIELD_NUMBER: _ClassVar[int]
        VALUE_FIELD_NUMBER: _ClassVar[int]
        key: str
        value: float
        def __init__(self, key: _Optional[str] = ..., value: _Optional[float] = ...) -> None: ...
    SUCCESS_FIELD_NUMBER: _ClassVar[int]
    POSITIONS_FIELD_NUMBER: _ClassVar[int]
    QUATERNIONS_FIELD_NUMBER: _ClassVar[int]
    WAYPOINT_INDICES_FIELD_NUMBER: _ClassVar[int]
    REPAIRS_FIELD_NUMBER: _ClassVar[int]
    SEGMENTS_FIELD_NUMBER: _ClassVar[int]
    STEPS_FIELD_NUMBER: _ClassVar[int]
    REGRASPS_FIELD_NUMBER: _ClassVar[int]
    KEPT_SHARE_FIELD_NUMBER: _ClassVar[int]
    HAND_FIELD_NUMBER: _ClassVar[int]
    MODEL_VERSION_FIELD_NUMBER: _ClassVar[int]
    TIMINGS_FIELD_NUMBER: _ClassVar[int]
    success: bool
    positions: Array
    quaternions: Array
    waypoint_indices: _containers.RepeatedScalarFieldContainer[int]
    repairs: _containers.RepeatedCompositeFieldContainer[WaypointRepair]
    segments: _containers.RepeatedCompositeFieldContainer[SegmentReport]
    steps: _containers.RepeatedCompositeFieldContainer[PlanStep]
    regrasps: _containers.RepeatedScalarFieldContainer[int]
    kept_share: float
    hand: str
    model_version: str
    timings: _containers.ScalarMap[str, float]
    def __init__(self, success: _Optional[bool] = ..., positions: _Optional[_Union[Array, _Mapping]] = ..., quaternions: _Optional[_Union[Array, _Mapping]] = ..., waypoint_indices: _Optional[_Iterable[int]] = ..., repairs: _Optional[_Iterable[_Union[WaypointRepair, _Mapping]]] = ..., segments: _Optional[_Iterable[_Union[SegmentReport, _Mapping]]] = ..., steps: _Optional[_Iterable[_Union[PlanStep, _Mapping]]] = ..., regrasps: _Optional[_Iterable[int]] = ..., kept_share: _Optional[float] = ..., hand: _Optional[str] = ..., model_version: _Optional[str] = ..., timings: _Optional[_Mapping[str, float]] = ...) -> None: ...

class RobotPreview(_message.Message):
    __slots__ = ("vertices", "faces", "spheres", "pads", "tips")
    VERTICES_FIELD_NUMBER: _ClassVar[int]
    FACES_FIELD_NUMBER: _ClassVar[int]
    SPHERES_FIELD_NUMBER: _ClassVar[int]
    PADS_FIELD_NUMBER: _ClassVar[int]
    TIPS_FIELD_NUMBER: _ClassVar[int]
    vertices: Array
    faces: Array
    spheres: Array
    pads: Array
    tips: Array
    def __init__(self, vertices: _Optional[_Union[Array, _Mapping]] = ..., faces: _Optional[_Union[Array, _Mapping]] = ..., spheres: _Optional[_Union[Array, _Mapping]] = ..., pads: _Optional[_Union[Array, _Mapping]] = ..., tips: _Optional[_Union[Array, _Mapping]] = ...) -> None: ...

class RobotPublic(_message.Message):
    __slots__ = ("name", "builtin", "dof", "joint_names", "lower", "upper", "fingertips", "num_spheres", "source", "warnings", "palm", "format", "surface_points", "pad_area_cm2", "couplings", "ignored", "meshes", "registration_s", "stored_bytes", "view_url", "preview")
    NAME_FIELD_NUMBER: _ClassVar[int]
    BUILTIN_FIELD_NUMBER: _ClassVar[int]
    DOF_FIELD_NUMBER: _ClassVar[int]
    JOINT_NAMES_FIELD_NUMBER: _ClassVar[int]
    LOWER_FIELD_NUMBER: _ClassVar[int]
    UPPER_FIELD_NUMBER: _ClassVar[int]
    FINGERTIPS_FIELD_NUMBER: _ClassVar[int]
    NUM_SPHERES_FIELD_NUMBER: _ClassVar[int]
    SOURCE_FIELD_NUMBER: _ClassVar[int]
    WARNINGS_FIELD_NUMBER: _ClassVar[int]
    PALM_FIELD_NUMBER: _ClassVar[int]
    FORMAT_FIELD_NUMBER: _ClassVar[int]
    SURFACE_POINTS_FIELD_NUMBER: _ClassVar[int]
    PAD_AREA_CM2_FIELD_NUMBER: _ClassVar[int]
    COUPLINGS_FIELD_NUMBER: _ClassVar[int]
    IGNORED_FIELD_NUMBER: _ClassVar[int]
    MESHES_FIELD_NUMBER: _ClassVar[int]
    REGISTRATION_S_FIELD_NUMBER: _ClassVar[int]
    STORED_BYTES_FIELD_NUMBER: _ClassVar[int]
    VIEW_URL_FIELD_NUMBER: _ClassVar[int]
    PREVIEW_FIELD_NUMBER: _ClassVar[int]
    name: str
    builtin: bool
    dof: int
    joint_names: _containers.RepeatedScalarFieldContainer[str]
    lower: _containers.RepeatedScalarFieldContainer[float]
    upper: _containers.RepeatedScalarFieldContainer[float]
    fingertips: _containers.RepeatedScalarFieldContainer[str]
    num_spheres: int
    source: str
    warnings: _containers.RepeatedScalarFieldContainer[str]
    palm: str
    format: str
    surface_points: int
    pad_area_cm2: _containers.RepeatedScalarFieldContainer[float]
    couplings: _containers.RepeatedScalarFieldContainer[str]
    ignored: _containers.RepeatedScalarFieldContainer[str]
    meshes: int
    registration_s: float
    stored_bytes: int
    view_url: str
    preview: RobotPreview
    def __init__(self, name: _Optional[str] = ..., builtin: _Optional[bool] = ..., dof: _Optional[int] = ..., joint_names: _Optional[_Iterable[str]] = ..., lower: _Optional[_Iterable[float]] = ..., upper: _Optional[_Iterable[float]] = ..., fingertips: _Optional[_Iterable[str]] = ..., num_spheres: _Optional[int] = ..., source: _Optional[str] = ..., warnings: _Optional[_Iterable[str]] = ..., palm: _Optional[str] = ..., format: _Optional[str] = ..., surface_points: _Optional[int] = ..., pad_area_cm2: _Optional[_Iterable[float]] = ..., couplings: _Optional[_Iterable[str]] = ..., ignored: _Optional[_Iterable[str]] = ..., meshes: _Optional[int] = ..., registration_s: _Optional[float] = ..., stored_bytes: _Optional[int] = ..., view_url: _Optional[str] = ..., preview: _Optional[_Union[RobotPreview, _Mapping]] = ...) -> None: ...

class ListRobotsRequest(_message.Message):
    __slots__ = ()
    def __init__(self) -> None: ...

class RobotList(_message.Message):
    __slots__ = ("robots",)
    ROBOTS_FIELD_NUMBER: _ClassVar[int]
    robots: _containers.RepeatedCompositeFieldContainer[RobotPublic]
    def __init__(self, robots: _Optional[_Iterable[_Union[RobotPublic, _Mapping]]] = ...) -> None: ...

class RobotRegister(_message.Message):
    __slots__ = ("name", "urdf", "fingertips", "tip_offsets", "mjcf", "archive", "description", "palm", "rest", "approach_axis")
    class RestEntry(_message.Message):
        __slots__ = ("key", "value")
        KEY_FIELD_NUMBER: _ClassVar[int]
        VALUE_FIELD_NUMBER: _ClassVar[int]
        key: str
        value: float
        def __init__(self, key: _Optional[str] = ..., value: _Optional[float] = ...) -> None: ...
    NAME_FIELD_NUMBER: _ClassVar[int]
    URDF_FIELD_NUMBER: _ClassVar[int]
    FINGERTIPS_FIELD_NUMBER: _ClassVar[int]
    TIP_OFFSETS_FIELD_NUMBER: _ClassVar[int]
    MJCF_FIELD_NUMBER: _ClassVar[int]
    ARCHIVE_FIELD_NUMBER: _ClassVar[int]
    DESCRIPTION_FIELD_NUMBER: _ClassVar[int]
    PALM_FIELD_NUMBER: _ClassVar[int]
    REST_FIELD_NUMBER: _ClassVar[int]
    APPROACH_AXIS_FIELD_NUMBER: _ClassVar[int]
    name: str
    urdf: str
    fingertips: _containers.RepeatedScalarFieldContainer[str]
    tip_offsets: Array
    mjcf: str
    archive: bytes
    description: str
    palm: str
    rest: _containers.ScalarMap[str, float]
    approach_axis: _containers.RepeatedScalarFieldContainer[float]
    def __init__(self, name: _Optional[str] = ..., urdf: _Optional[str] = ..., fingertips: _Optional[_Iterable[str]] = ..., tip_offsets: _Optional[_Union[Array, _Mapping]] = ..., mjcf: _Optional[str] = ..., archive: _Optional[bytes] = ..., description: _Optional[str] = ..., palm: _Optional[str] = ..., rest: _Optional[_Mapping[str, float]] = ..., approach_axis: _Optional[_Iterable[float]] = ...) -> None: ...
