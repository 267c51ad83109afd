"""What the result viewer draws besides the result: the object's points, kept by the API that took the request.

The queue contract returns results, not requests, so the API keeps a bounded, subsampled copy of each object it enqueued
(at most ``MAX_VIEW_POINTS`` points, float32; least recently submitted dropped first); for a plan also its scene as
drawn (`manifoundation.server.api.plan_scenes`: obstacles, support plane, waypoints). A job submitted through another
API replica, or forgotten, is drawn from its result alone (contacts, forces, hand; a plan's path and steps).
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from manifoundation.contract import JobPublic, JobRequest, PlanRequest, SceneObstacle, ScenePublic
from manifoundation.contract.tasks import PointMotionTask, TargetPointsTask
from manifoundation.server.api.plan_scenes import evenly, scene_view

MAX_SCENES = 128


@dataclass
class _Scene:
    index: np.ndarray  # which of the request's points were kept
    points: np.ndarray
    normals: np.ndarray | None
    region_mask: np.ndarray | None
    targets: np.ndarray | None  # where the points should go (per-point tasks), float32
    obstacles: list[SceneObstacle] | None = None
    support_height: float | None = None
    waypoints: list[list[float]] | None = None


class SceneStore:
    """job id → subsampled object, LRU-bounded (128 × 4096 × (3 + 3) × 4 B ≈ 12.6 MB at most for syntheses; a
    plan adds its drawn obstacles, each bounded by `manifoundation.server.api.plan_scenes`)."""

    def __init__(self, size: int = MAX_SCENES) -> None:
        self.size = size
        self._scenes: OrderedDict[str, _Scene] = OrderedDict()

    def put(self, job_id: str, request: JobRequest) -> None:
        obj = request.object
        n = obj.num_points
        index = evenly(np.arange(n))
        scene = _Scene(
            index=index,
            points=obj.points[index].astype(np.float32),
            normals=None if obj.normals is None else obj.normals[index].astype(np.float32),
            region_mask=None if obj.region_mask is None else obj.region_mask[index],
            targets=_targets(request, index),
        )
        if isinstance(request, PlanRequest):
            scene.obstacles, scene.support_height, scene.waypoints = scene_view(request)
        self._scenes[job_id] = scene
        while len(self._scenes) > self.size:
            self._scenes.popitem(last=False)

    def view(self, job: JobPublic) -> ScenePublic:
        """The job with its object (when known) and the heatmap at the kept points."""
        scene = self._scenes.get(job.id)
        if scene is None:
            return ScenePublic(job=job)
        heatmap = None
        if job.result is not None and job.result.heatmap is not None and len(job.result.heatmap) > scene.index.max():
            heatmap = job.result.heatmap[scene.index].round(5).tolist()
        return ScenePublic(
            job=job,
            points=scene.points.round(5).tolist(),
            normals=None if scene.normals is None else scene.normals.round(4).tolist(),
            region_mask=None if scene.region_mask is None else scene.region_mask.astype(int).tolist(),
            heatmap=heatmap,
            target_points=None if scene.targets is None else scene.targets.round(5).tolist(),
            obstacles=scene.obstacles,
            support_height=scene.support_height,
            waypoints=scene.waypoints,
        )


def _targets(request: JobRequest, index: np.ndarray) -> np.ndarray | None:
    """The target the viewer draws for a per-point task: the points plus their motion, or the target cloud."""
    if isinstance(request, PlanRequest):
        return None
    task = request.task
    if isinstance(task, PointMotionTask):
        return (request.object.points[index] + task.motion[index]).astype(np.float32)
    if isinstance(task, TargetPointsTask):
        if task.correspondence == "index":
            return task.targets[index].astype(np.float32)
        return evenly(task.targets).astype(np.float32)
    return None


