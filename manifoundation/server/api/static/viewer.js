"use strict";
// Draws one job's result: the object's points coloured by the contact heatmap, the contacts, the force arrows,
// and the hand at its solved pose (palm frame from palm_position + palm_quaternion, a link from the palm to
// each fingertip at its contact, fingertip spheres); with the proposal's quality figures. A plan job is played
// step by step by plan_viewer.js.
const pathParts = window.location.pathname.split("/"); // /view/{id} or /v1/jobs/{id}/view
const jobId = decodeURIComponent(pathParts[1] === "view" ? pathParts[2] : pathParts[3]);
document.getElementById("job-id").textContent = jobId;
document.getElementById("back").href = "/" + mani.suffix;

function rotation(q) {  // (w, x, y, z) → 3×3 rows
  const [w, x, y, z] = q;
  return [
    [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
    [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
    [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
  ];
}
const col = (rows, i) => rows.map((r) => r[i]);

function extent(points) {
  if (!points || !points.length) return 0.1;
  let lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (const p of points) for (let i = 0; i < 3; i++) { lo[i] = Math.min(lo[i], p[i]); hi[i] = Math.max(hi[i], p[i]); }
  return Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) || 0.1;
}

function rows(tableId, pairs) {
  const body = document.querySelector("#" + tableId + " tbody");
  body.replaceChildren();
  for (const [k, v] of pairs) { const tr = document.createElement("tr"); mani.cell(tr, k); mani.cell(tr, v, "mono"); body.appendChild(tr); }
}

function fmt(v) {
  if (typeof v === "number") return Math.abs(v) > 0 && (Math.abs(v) < 1e-3 || Math.abs(v) > 1e4) ? v.toExponential(2) : v.toFixed(4);
  return mani.text(v);
}

function traces(scene, proposal) {
  const out = [];
  const pts = scene.points;
  const size = extent(pts || (proposal ? proposal.contact_points : null));
  if (pts) {
    const colour = scene.heatmap || (scene.region_mask ? scene.region_mask : pts.map((p) => p[2]));
    out.push({ type: "scatter3d", mode: "markers", name: scene.heatmap ? "object (heatmap)" : "object",
      x: col(pts, 0), y: col(pts, 1), z: col(pts, 2),
      marker: { size: 2, color: colour, colorscale: scene.heatmap ? "YlOrRd" : "Greys",
                showscale: !!scene.heatmap, colorbar: { title: "heat", len: 0.5 } } });
  }
  if (scene.target_points) {
    const t = scene.target_points;
    out.push({ type: "scatter3d", mode: "markers", name: "target", x: col(t, 0), y: col(t, 1), z: col(t, 2),
      marker: { size: 2, color: "#2ca02c", opacity: 0.6 } });
  }
  if (!proposal) return out;
  if (proposal.rollout_points) {
    const r = thin(proposal.rollout_points, 4096);
    out.push({ type: "scatter3d", mode: "markers", name: "rollout (simulated)", x: col(r, 0), y: col(r, 1),
      z: col(r, 2), marker: { size: 2, color: "#ff7f0e", opacity: 0.8 } });
  }
  if (proposal.contact_motions) out.push(...arrows(proposal.contact_points, proposal.contact_motions, 1.0,
    "post-contact motions", "#9467bd", size));
  const c = proposal.contact_points, f = proposal.forces;
  out.push({ type: "scatter3d", mode: "markers+text", name: "contacts", x: col(c, 0), y: col(c, 1), z: col(c, 2),
    text: proposal.fingertips, textposition: "top center", marker: { size: 7, color: "#d62728" } });
  const fmax = Math.max(...f.map((v) => Math.hypot(...v)), 0);
  if (fmax > 0) out.push(...arrows(c, f, 0.35 * size / fmax, "forces", "#1f77b4", size));
  if (!proposal.palm_position) return out;  // contacts without a robot: no hand to draw
  // The hand: palm frame, palm→fingertip links, fingertip spheres at the contacts.
  const palm = proposal.palm_position, R = rotation(proposal.palm_quaternion), a = 0.4 * size;
  ["#e41a1c", "#4daf4a", "#377eb8"].forEach((colour, k) => {
    out.push({ type: "scatter3d", mode: "lines", showlegend: k === 0, name: "palm frame", legendgroup: "palm",
      x: [palm[0], palm[0] + a * R[0][k]], y: [palm[1], palm[1] + a * R[1][k]], z: [palm[2], palm[2] + a * R[2][k]],
      line: { color: colour, width: 8 } });
  });
  if (proposal.hand_mesh && proposal.hand_mesh.vertices.length) {
    out.push(handMesh(proposal.hand_mesh));
  } else if (proposal.hand_spheres && proposal.hand_spheres.length) {
    out.push(sphereMesh(proposal.hand_spheres));
  } else {
    const hx = [], hy = [], hz = [];
    c.forEach((p) => { hx.push(palm[0], p[0], null); hy.push(palm[1], p[1], null); hz.push(palm[2], p[2], null); });
    out.push({ type: "scatter3d", mode: "lines", name: "hand (palm → fingertips)", x: hx, y: hy, z: hz,
      line: { color: "#8c564b", width: 10 }, opacity: 0.6 });
  }
  out.push({ type: "scatter3d", mode: "markers", name: "palm", x: [palm[0]], y: [palm[1]], z: [palm[2]],
    marker: { size: 14, color: "#8c564b", symbol: "square" } });
  out.push({ type: "scatter3d", mode: "markers", name: "fingertips", x: col(c, 0), y: col(c, 1), z: col(c, 2),
    marker: { size: 12, color: "#ff7f0e", opacity: 0.35 } });
  return out;
}

// Every k-th row so that at most `limit` are drawn.
function thin(rows, limit) {
  const k = Math.max(1, Math.ceil(rows.length / limit));
  return k === 1 ? rows : rows.filter((_, i) => i % k === 0);
}

// Lines from each start point along its vector (× scale) with a cone at the head.
function arrows(starts, vectors, scale, name, colour, size) {
  const heads = vectors.map((v, i) => starts[i].map((s, k) => s + v[k] * scale));
  const lx = [], ly = [], lz = [];
  starts.forEach((p, i) => { lx.push(p[0], heads[i][0], null); ly.push(p[1], heads[i][1], null); lz.push(p[2], heads[i][2], null); });
  return [
    { type: "scatter3d", mode: "lines", name, legendgroup: name, x: lx, y: ly, z: lz, line: { color: colour, width: 6 } },
    { type: "cone", name: name + " heads", legendgroup: name, showlegend: false, showscale: false, anchor: "tip",
      sizemode: "absolute", sizeref: 0.08 * size, x: col(heads, 0), y: col(heads, 1), z: col(heads, 2),
      u: col(vectors, 0), v: col(vectors, 1), w: col(vectors, 2), colorscale: [[0, colour], [1, colour]] },
  ];
}

// The hand's collision meshes at its solved pose (what the contacts were verified on), world metres.
function handMesh(mesh) {
  const v = mesh.vertices, f = mesh.faces;
  return { type: "mesh3d", name: "hand (collision meshes)", showlegend: true, x: col(v, 0), y: col(v, 1), z: col(v, 2),
    i: col(f, 0), j: col(f, 1), k: col(f, 2), color: "#c49c94", opacity: 0.55, flatshading: true, hoverinfo: "skip" };
}

// The hand at its solved pose as one mesh of its collision spheres ([x, y, z, r] rows, metres).
function sphereMesh(spheres) {
  const rings = 6, segments = 10, x = [], y = [], z = [], i = [], j = [], k = [];
  spheres.forEach(([cx, cy, cz, r]) => {
    const base = x.length;
    for (let a = 0; a <= rings; a++) {
      const theta = (Math.PI * a) / rings;
      for (let b = 0; b < segments; b++) {
        const phi = (2 * Math.PI * b) / segments;
        x.push(cx + r * Math.sin(theta) * Math.cos(phi));
        y.push(cy + r * Math.sin(theta) * Math.sin(phi));
        z.push(cz + r * Math.cos(theta));
      }
    }
    for (let a = 0; a < rings; a++) {
      for (let b = 0; b < segments; b++) {
        const p = base + a * segments + b, q = base + a * segments + ((b + 1) % segments);
        i.push(p, q); j.push(p + segments, p + segments); k.push(q, q + segments);
      }
    }
  });
  return { type: "mesh3d", name: "hand (collision spheres)", showlegend: true, x, y, z, i, j, k,
    color: "#c49c94", opacity: 0.35, flatshading: true, hoverinfo: "skip" };
}

// The simulated grasp test (options.simulate): its verdict, then each push direction's displacement and turn.
function physicsRows(physics) {
  if (!physics) return [["physics test", "- (not run: options.simulate false, or not a rigid grasp with a hand)"]];
  const trials = (physics.trials || []).map((t) => ["push " + t.direction,
    (t.held ? "held" : "moved") + ", " + (1000 * t.translation).toFixed(1) + " mm, " + t.rotation.toFixed(1) + "°"]);
  const gaps = (physics.tip_gaps || []).map((g) => (1000 * g).toFixed(1)).join(", ");
  const m = physics.motion;
  const motion = m ? [["motion: final error", (1000 * m.translation_error).toFixed(1) + " mm, "
    + m.rotation_error.toFixed(1) + "°" + (m.dropped ? " (dropped)" : "")]] : [];
  const name = physics.test === "motion" ? "physics test (target motion)" : "physics test";
  return [[name, physics.held ? (physics.test === "motion" ? "reached" : "held") : "failed (" + physics.reason + ")"],
    ["fingertip gaps (mm)", gaps || "-"], ["touching after squeeze", physics.touching_after_squeeze], ...motion,
    ...trials];
}

function draw(scene, index) {
  const job = scene.job, result = job.result;
  const proposal = result && result.proposals.length ? result.proposals[index] : null;
  if (proposal) {
    const q = proposal.quality;
    rows("quality", [["verified", q.success ? "yes" : "no"], ["reason", q.reason], ["contacts from", proposal.contact_source || "-"],
      ["iterations", q.iterations], ["wrench residual", fmt(q.wrench_residual)],
      ["max tip distance (m)", fmt(q.max_tip_distance)], ["penetration (m)", fmt(q.penetration_depth)],
      ["self-collision (m)", fmt(q.self_collision_depth)], ["Ferrari–Canny ε", q.epsilon == null ? "- (not computed)" : fmt(q.epsilon)],
      ["verified on", q.geometry || "-"], ["failed criteria", (q.failures || []).join(", ") || "-"],
      ...(proposal.shape_error == null ? [] : [["shape error (2 m cube)", fmt(proposal.shape_error)]]),
      ...physicsRows(q.physics)]);
    rows("hand", proposal.palm_position ? [["hand", result.hand],
      ["palm position", proposal.palm_position.map(fmt).join(", ")],
      ["palm quaternion", proposal.palm_quaternion.map(fmt).join(", ")],
      ...proposal.joint_names.map((n, i) => [n, fmt(proposal.joint_values[i])])] : [["hand", "none (contacts for any gripper)"]]);
  } else {
    rows("quality", [["proposals", "none"], ...(job.error ? [["error", job.error.type + ": " + job.error.error]] : [])]);
    rows("hand", []);
  }
  rows("timings", Object.entries({ ...(result ? result.timings : {}), ...job.timings }).map(([k, v]) => [k, mani.seconds(v)]));
  document.getElementById("note").textContent = scene.points ? "" :
    "The object's points are not known to this API process; showing the result only.";
  try {
  Plotly.react("scene", traces(scene, proposal), {
    margin: { l: 0, r: 0, t: 0, b: 0 }, legend: { x: 0, y: 1 },
    scene: { aspectmode: "data", xaxis: { title: "x (m)" }, yaxis: { title: "y (m)" }, zaxis: { title: "z (m)" } },
  }, { responsive: true });
  } catch (err) {
    document.getElementById("error").textContent = "3D view unavailable (WebGL): " + err.message;
  }
}

async function load() {
  try {
    const scene = await mani.fetchJson("/v1/jobs/" + encodeURIComponent(jobId) + "/scene");
    const job = scene.job;
    document.getElementById("status").textContent = job.state + (job.state === "running" ? " · " + job.progress.stage : "");
    document.getElementById("status").className = "state-" + job.state;
    if (job.kind === "plan") {
      const p = job.progress;
      if (job.state === "running" && p.total) document.getElementById("status").textContent += " " + p.completed + "/" + p.total;
      if (job.plan) showPlan(scene); else rows("quality", job.error ? [["error", job.error.type + ": " + job.error.error]] : []);
      if (!["succeeded", "failed", "cancelled", "expired"].includes(job.state)) setTimeout(load, 1000);
      return;
    }
    const select = document.getElementById("proposal");
    const n = job.result ? job.result.proposals.length : 0;
    select.replaceChildren(...Array.from({ length: n }, (_, i) => new Option("proposal " + i, String(i))));
    select.onchange = () => draw(scene, Number(select.value));
    draw(scene, 0);
    if (!["succeeded", "failed", "cancelled", "expired"].includes(job.state)) setTimeout(load, 1000);
  } catch (err) {
    document.getElementById("error").textContent = "could not load the job: " + err.message;
  }
}
load();
