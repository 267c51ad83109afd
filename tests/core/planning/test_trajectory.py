import pickle

import numpy as np
import pytest
import trimesh

from manifoundation.core.planning import BoxObstacle, InfeasibleWaypoint, NoPathFound, PlanOptions, Pose, SupportPlane
from manifoundation.core.planning.trajectory import plan_trajectory
from tests.core.planning.conftest import scene_with

FAST = PlanOptions(time_limit=2.0, translation_step=0.02, rotation_step=0.2, seed=3, contacts=False)


def _inside_box(points, box: BoxObstacle) -> np.ndarray:
    local = box.pose.inverse().apply(points)
    return np.all(np.abs(local) < np.asarray(box.size) / 2, axis=1)


def test_straight_path_through_a_free_scene_stays_straight(block):
    scene = scene_with(block, [], SupportPlane(0.0))
    start = Pose(np.array([-0.2, 0.0, 0.1]))
    goal = Pose(np.array([0.2, 0.1, 0.15]), np.array([np.cos(0.3), 0.0, 0.0, np.sin(0.3)]))
    traj = plan_trajectory(scene, start, [goal], FAST)
    assert traj.segments[0].straight
    pos = np.array([p.position for p in traj.poses])
    line = goal.position - start.position
    t = (pos - start.position) @ line / (line @ line)
    off_line = pos - (start.position + t[:, None] * line)
    assert np.abs(off_line).max() < 1e-9 and np.all(np.diff(t) > 0)
    steps = np.linalg.norm(np.diff(pos, axis=0), axis=1)
    angles = [a.angle_to(b) for a, b in zip(traj.poses[:-1], traj.poses[1:], strict=True)]
    assert steps.max() <= FAST.translation_step + 1e-12 and max(angles) <= FAST.rotation_step + 1e-12
    # a 0.6 rad turn about z split evenly: each step turns the same angle about the same axis
    assert np.ptp(angles) < 1e-9
    np.testing.assert_allclose(traj.poses[-1].matrix(), goal.matrix(), atol=1e-12)


def test_a_wall_between_waypoints_is_gone_around(block, wall):
    mesh = block[0]
    scene = scene_with(block, [wall], SupportPlane(0.0))
    start, goal = Pose(np.array([-0.15, 0.0, 0.1])), Pose(np.array([0.15, 0.0, 0.1]))
    traj = plan_trajectory(scene, start, [goal], FAST)
    seg = traj.segments[0]
    assert not seg.straight and seg.raw_states >= seg.simplified_states >= 3
    # independent check: dense surface samples of the object never inside the wall (analytic box test)
    surface = trimesh.sample.sample_surface(mesh, 3000, seed=1)[0]
    for pose in traj.poses:
        assert not _inside_box(pose.apply(surface), wall).any()
        assert pose.apply(np.asarray(mesh.vertices))[:, 2].min() > -1e-3  # above the table
    pos = np.array([p.position for p in traj.poses])
    assert np.abs(pos[:, 1]).max() > 0.2 or pos[:, 2].max() > 0.3  # around the side or over the top


def test_same_seed_same_path_even_after_other_plans(block, wall):
    scene = scene_with(block, [wall], SupportPlane(0.0))
    start, goal = Pose(np.array([-0.15, 0.0, 0.1])), Pose(np.array([0.15, 0.0, 0.1]))
    a = plan_trajectory(scene, start, [goal], FAST)
    plan_trajectory(scene, start, [goal], PlanOptions(time_limit=2.0, seed=11, contacts=False))  # in between
    b = plan_trajectory(scene, start, [goal], FAST)
    assert len(a.poses) == len(b.poses)
    for p, q in zip(a.poses, b.poses, strict=True):
        np.testing.assert_array_equal(p.matrix(), q.matrix())


def test_waypoint_inside_an_obstacle_is_moved_to_the_nearest_free_position(block, wall):
    scene = scene_with(block, [wall], SupportPlane(0.0))
    start = Pose(np.array([-0.15, 0.0, 0.1]))
    inside = Pose(np.array([0.005, 0.0, 0.1]))  # the block (4 cm along x) straddles the 2 cm wall
    traj = plan_trajectory(scene, start, [inside, Pose(np.array([0.15, 0.0, 0.1]))], FAST)
    (rep,) = traj.repairs
    assert rep.index == 0 and rep.obstacles == ["wall"]
    # analytic nearest: +x until the block's face (x − 0.02) clears the wall's (0.01): 2.5 cm, plus 2 mm clearance
    assert abs(rep.distance - 0.027) < 1.5e-3
    np.testing.assert_allclose(rep.repaired.position, [0.005 + rep.distance, 0, 0.1], atol=2e-3)
    np.testing.assert_array_equal(rep.repaired.quaternion, inside.quaternion)
    assert traj.poses[traj.waypoint_indices[0]] is rep.repaired


def test_waypoint_in_collision_is_reported_when_asked(block, wall):
    scene = scene_with(block, [wall], SupportPlane(0.0))
    opts = PlanOptions(repair="report", contacts=False)
    with pytest.raises(InfeasibleWaypoint, match=r"waypoints\[1\].*wall") as err:
        plan_trajectory(scene, Pose(np.array([-0.15, 0, 0.1])),
                        [Pose(np.array([-0.1, 0, 0.1])), Pose(np.array([0.0, 0, 0.1]))], opts)  # fmt: skip
    assert err.value.field == "waypoints[1]" and err.value.obstacles == ["wall"]
    again = pickle.loads(pickle.dumps(err.value))  # errors cross process boundaries in the workers
    assert str(again) == str(err.value) and again.field == "waypoints[1]"


def test_start_in_collision_and_unrepairable_waypoints_are_errors(block, wall):
    scene = scene_with(block, [wall], SupportPlane(0.0))
    with pytest.raises(InfeasibleWaypoint, match="start"):
        plan_trajectory(scene, Pose(np.array([0.0, 0, 0.1])), [Pose(np.array([0.2, 0, 0.1]))], FAST)
    deep = BoxObstacle(np.array([0.6, 0.6, 0.6]), Pose(np.array([0.5, 0.0, 0.3])), "crate")
    scene = scene_with(block, [deep], None)
    with pytest.raises(InfeasibleWaypoint, match=r"waypoints\[0\].*within 0.1 m"):
        plan_trajectory(scene, Pose(np.array([-0.2, 0, 0.3])), [Pose(np.array([0.5, 0, 0.3]))], FAST)


def test_below_the_table_is_lifted_onto_it(block):
    scene = scene_with(block, [], SupportPlane(0.0, tolerance=1e-3))
    traj = plan_trajectory(scene, Pose(np.array([0.0, 0, 0.1])), [Pose(np.array([0.1, 0, 0.01]))], FAST)
    (rep,) = traj.repairs
    assert rep.obstacles == ["support_plane"]
    # the block's bottom (z − 0.03) may be 1 mm below the table: lifted ≈ 1.9 cm, plus the 2 mm clearance
    assert abs(rep.repaired.position[2] - 0.031) < 1.5e-3 and abs(rep.repaired.position[0] - 0.1) < 1e-9


def test_enclosed_goal_is_no_path_found(block):
    cage = [BoxObstacle(np.array(s), Pose(np.array(c)), n) for s, c, n in [
        ([0.3, 0.3, 0.02], [0.5, 0, 0.01], "floor"), ([0.3, 0.3, 0.02], [0.5, 0, 0.29], "lid"),
        ([0.02, 0.3, 0.3], [0.35, 0, 0.15], "w1"), ([0.02, 0.3, 0.3], [0.65, 0, 0.15], "w2"),
        ([0.3, 0.02, 0.3], [0.5, 0.15, 0.15], "w3"), ([0.3, 0.02, 0.3], [0.5, -0.15, 0.15], "w4"),
    ]]  # fmt: skip
    scene = scene_with(block, cage, None)
    with pytest.raises(NoPathFound, match=r"start to waypoints\[0\]") as err:
        plan_trajectory(scene, Pose(np.array([0.0, 0, 0.15])), [Pose(np.array([0.5, 0, 0.15]))],
                        PlanOptions(time_limit=0.3, contacts=False))  # fmt: skip
    assert str(pickle.loads(pickle.dumps(err.value))) == str(err.value)
