"use strict";
const STATES = ["queued", "running", "succeeded", "failed", "cancelled", "expired"];
const COLOURS = { queued: "#9a6700", running: "#0969da", succeeded: "#1a7f37", failed: "#cf222e",
                  cancelled: "#6e7781", expired: "#b3b3b3" };
const PERIOD_MS = 2000;

function jobLink(id) {
  const a = document.createElement("a");
  a.href = "/view/" + encodeURIComponent(id) + mani.suffix;
  a.textContent = id;
  a.className = "mono job-link";
  return a;
}

function fill(tableId, rows, render) {
  const body = document.querySelector("#" + tableId + " tbody");
  body.replaceChildren();
  for (const item of rows) { const tr = document.createElement("tr"); render(tr, item); body.appendChild(tr); }
  if (!rows.length) { const tr = document.createElement("tr"); mani.cell(tr, "none"); body.appendChild(tr); }
}

function plots(data) {
  const t = data.series.map((s) => new Date(s.t * 1000));
  const layout = { margin: { l: 40, r: 50, t: 10, b: 50 }, legend: { orientation: "h", y: -0.3 }, height: 250,
                  yaxis: { rangemode: "tozero" } };
  Plotly.react("states-plot", STATES.map((state) => ({
    x: t, y: data.series.map((s) => s.by_state[state] || 0), name: state, mode: "lines",
    line: { color: COLOURS[state] },
  })), layout, { displayModeBar: false, responsive: true });
  const rate = data.series.map((s, i) => {
    if (i === 0) return 0;
    const p = data.series[i - 1];
    const done = s.completed_total + s.failed_total - p.completed_total - p.failed_total;
    return Math.max(0, done / Math.max(1e-9, s.t - p.t));
  });
  Plotly.react("depth-plot", [
    { x: t, y: data.series.map((s) => s.depth), name: "queue depth", mode: "lines" },
    { x: t, y: data.series.map((s) => s.running), name: "running", mode: "lines" },
    { x: t, y: rate, name: "finished/s", mode: "lines", yaxis: "y2" },
  ], { ...layout, yaxis2: { overlaying: "y", side: "right", title: "jobs/s", rangemode: "tozero" } },
  { displayModeBar: false, responsive: true });
}

function render(data) {
  document.getElementById("backend").textContent = data.backend;
  document.getElementById("queue-up").textContent = data.queue_up ? "up" : "DOWN";
  document.getElementById("updated").textContent = mani.clock(data.now);
  const s = data.stats || {};
  document.getElementById("depth").textContent = mani.text(s.depth);
  document.getElementById("running").textContent = mani.text(s.running);
  document.getElementById("throughput").textContent = data.throughput_per_s.toFixed(2);
  document.getElementById("p50").textContent = mani.seconds(data.latency_p50);
  document.getElementById("p99").textContent = mani.seconds(data.latency_p99);
  document.getElementById("nworkers").textContent = data.workers.length;
  document.getElementById("totals").textContent = mani.text(s.completed_total) + " / " + mani.text(s.failed_total);
  document.getElementById("verified").textContent = data.verified_rate == null ? "–"
    : Math.round(100 * data.verified_rate) + " % (" + data.verified_grasps + "/" + data.finished_jobs + ")";
  document.getElementById("ndead").textContent = mani.text(s.dead_letters);
  fill("workers", data.workers, (tr, w) => {
    mani.cell(tr, w.id, "mono");
    mani.cell(tr, w.host + " / " + w.pid);
    mani.cell(tr, (data.now - w.last_heartbeat).toFixed(1) + " s ago");
    mani.cell(tr, w.current_job ? jobLink(w.current_job) : "idle");
    mani.cell(tr, w.jobs_done);
    mani.cell(tr, w.model_loaded ? (w.model_version || "loaded") : "not loaded");
  });
  fill("recent", data.recent, (tr, j) => {
    mani.cell(tr, jobLink(j.id));
    mani.cell(tr, j.state, "state-" + j.state);
    const p = j.progress || {};
    mani.cell(tr, p.stage + (p.iteration ? " " + p.iteration + "/" + (p.max_iterations || "?") : ""));
    mani.cell(tr, mani.clock(j.created_at));
    mani.cell(tr, j.finished_at ? mani.seconds(j.finished_at - j.created_at) : "…");
    mani.cell(tr, j.worker || "");
    mani.cell(tr, j.error ? j.error.type + ": " + j.error.error : "", "error");
  });
  fill("dead", data.dead_letters, (tr, d) => {
    mani.cell(tr, jobLink(d.job_id));
    mani.cell(tr, d.deliveries);
    mani.cell(tr, mani.clock(d.failed_at));
    mani.cell(tr, d.error.type + ": " + d.error.error, "error");
  });
  plots(data);
}

async function refresh() {
  try {
    render(await mani.fetchJson("/dashboard/data"));
    document.getElementById("error").textContent = "";
  } catch (err) {
    document.getElementById("error").textContent = "could not load /dashboard/data: " + err.message;
  }
}
refresh();
setInterval(refresh, PERIOD_MS);
