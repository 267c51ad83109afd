"use strict";
// Plays a plan job (POST /v1/plans): the scene's obstacles and support plane, the object's path and waypoints,
// and per step the object at its pose, the hand (its posed meshes when the plan asked for them, else its collision
// spheres) and the contacts with their forces. A slider picks the step, "play" walks through them. Uses viewer.js's
// rotation, traces, rows, fmt (loaded after this file; called only once both are).

function obstacleTraces(scene) {
  const out = [];
  (scene.obstacles || []).forEach((o, n) => {
    const v = o.vertices;
    if (o.faces && o.faces.length) {
      out.push({ type: "mesh3d", name: o.name, legendgroup: "obstacles", showlegend: true, opacity: 0.35,
        color: n % 2 ? "#7f7f7f" : "#a0a0a0", flatshading: true, hoverinfo: "name",
        x: col(v, 0), y: col(v, 1), z: col(v, 2), i: col(o.faces, 0), j: col(o.faces, 1), k: col(o.faces, 2) });
    } else {
      out.push({ type: "scatter3d", mode: "markers", name: o.name, x: col(v, 0), y: col(v, 1), z: col(v, 2),
        marker: { size: 2, color: "#7f7f7f" } });
    }
  });
  return out;
}

function planeTrace(height, positions) {
  const xs = col(positions, 0), ys = col(positions, 1), m = 0.15;
  const x0 = Math.min(...xs) - m, x1 = Math.max(...xs) + m, y0 = Math.min(...ys) - m, y1 = Math.max(...ys) + m;
  return { type: "mesh3d", name: "support plane", x: [x0, x1, x1, x0], y: [y0, y0, y1, y1], z: [height, height, height, height],
    i: [0, 0], j: [1, 2], k: [2, 3], color: "#d2b48c", opacity: 0.3, hoverinfo: "skip", showlegend: true };
}

function placedPoints(points, position, quaternion) {
  const R = rotation(quaternion);
  return points.map((p) => [0, 1, 2].map((r) => R[r][0] * p[0] + R[r][1] * p[1] + R[r][2] * p[2] + position[r]));
}

// The traces of pose k: the fixed scene, the path, and the object with the step's hand and contacts.
function planTraces(scene, plan, k) {
  const out = obstacleTraces(scene);
  if (scene.support_height !== null && scene.support_height !== undefined) out.push(planeTrace(scene.support_height, plan.positions));
  const P = plan.positions;
  out.push({ type: "scatter3d", mode: "lines", name: "path", x: col(P, 0), y: col(P, 1), z: col(P, 2),
    line: { color: "#2ca02c", width: 4 } });
  const W = plan.waypoint_indices.map((i) => P[i]);
  out.push({ type: "scatter3d", mode: "markers", name: "waypoints (as planned)", x: col(W, 0), y: col(W, 1), z: col(W, 2),
    marker: { size: 5, color: "#2ca02c", symbol: "diamond" } });
  if (plan.repairs && plan.repairs.length) {
    const asked = plan.repairs.map((r) => r.requested.position);
    out.push({ type: "scatter3d", mode: "markers", name: "waypoints (requested, repaired)", x: col(asked, 0),
      y: col(asked, 1), z: col(asked, 2), marker: { size: 5, color: "#d62728", symbol: "x" } });
  }
  const step = k < plan.steps.length ? plan.steps[k] : null;
  const moved = scene.points ? { points: placedPoints(scene.points, P[k], plan.quaternions[k]) } : {};
  return out.concat(traces(moved, step && step.proposal ? step.proposal : null));
}

function drawPlan(scene, k) {
  const job = scene.job, plan = job.plan;
  const step = k < plan.steps.length ? plan.steps[k] : null;
  const failed = plan.steps.filter((s) => !s.success).map((s) => s.index);
  rows("plan", [["success", plan.success], ["poses", plan.positions.length], ["steps", plan.steps.length],
    ["kept share", fmt(plan.kept_share)], ["re-grasps at", plan.regrasps.join(", ") || "-"],
    ["failed steps", failed.join(", ") || "-"], ["repaired waypoints", plan.repairs.map((r) => r.index).join(", ") || "-"],
    ["step " + k, step ? step.grasp + (step.success ? " (verified, free)" : " (FAILED)") : "last pose"],
    ["dropped", step && step.dropped ? step.dropped : "-"], ["hand meets", step && step.hand_collisions.length ? step.hand_collisions.join(", ") : "-"]]);
  const proposal = step && step.proposal ? step.proposal : null;
  if (proposal) {
    const q = proposal.quality;
    rows("quality", [["success", q.success], ["converged", q.converged], ["iterations", q.iterations],
      ["wrench residual", fmt(q.wrench_residual)], ["max tip distance (m)", fmt(q.max_tip_distance)],
      ["penetration (m)", fmt(q.penetration_depth)], ["failed criteria", (q.failures || []).join(", ") || "-"]]);
    rows("hand", [["hand", plan.hand], ["palm position", proposal.palm_position.map(fmt).join(", ")],
      ...proposal.joint_names.map((n, i) => [n, fmt(proposal.joint_values[i])])]);
  } else {
    rows("quality", [["proposal", "none at this pose"]]);
    rows("hand", [["hand", plan.hand]]);
  }
  rows("timings", Object.entries({ ...plan.timings, ...job.timings }).map(([name, v]) => [name, mani.seconds(v)]));
  document.getElementById("step-label").textContent = "pose " + k + " of " + (plan.positions.length - 1);
  try {
    Plotly.react("scene", planTraces(scene, plan, k), {
      margin: { l: 0, r: 0, t: 0, b: 0 }, legend: { x: 0, y: 1 }, uirevision: "plan",
      scene: { aspectmode: "data", xaxis: { title: "x (m)" }, yaxis: { title: "y (m)" }, zaxis: { title: "z (m)" } },
    }, { responsive: true });
  } catch (err) {
    document.getElementById("error").textContent = "3D view unavailable (WebGL): " + err.message;
  }
}

let planTimer = null;

function showPlan(scene) {
  const plan = scene.job.plan;
  document.getElementById("player").hidden = false;
  document.getElementById("plan-panel").hidden = false;
  document.getElementById("proposal").hidden = true;
  const slider = document.getElementById("step"), play = document.getElementById("play");
  slider.max = String(plan.positions.length - 1);
  slider.oninput = () => drawPlan(scene, Number(slider.value));
  play.onclick = () => {
    if (planTimer) { clearInterval(planTimer); planTimer = null; play.textContent = "▶ play"; return; }
    if (Number(slider.value) >= Number(slider.max)) slider.value = "0";
    play.textContent = "❚❚ pause";
    planTimer = setInterval(() => {
      if (Number(slider.value) >= Number(slider.max)) { clearInterval(planTimer); planTimer = null; play.textContent = "▶ play"; return; }
      slider.value = String(Number(slider.value) + 1);
      drawPlan(scene, Number(slider.value));
    }, 300);
  };
  drawPlan(scene, Number(slider.value));
}
