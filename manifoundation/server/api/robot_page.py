"""The page of `GET /v1/robots/{name}/view`: a registered hand at rest (coarse meshes, collision spheres, contact
pads, fingertips), drawn by the offline plotly bundle (`/static/plotly.min.js`). The data is inlined in the page
(the route already checked the caller's key), JSON-escaped so it cannot close the script element."""

from __future__ import annotations

import html
import json
from typing import Any

_PAGE = """<!doctype html>
<html><head><meta charset="utf-8"><title>{title}</title>
<script src="/static/plotly.min.js"></script>
<style>body{{font-family:sans-serif;margin:0}} #plot{{width:100vw;height:92vh}} p{{margin:6px 12px}}</style>
</head><body><p>{summary} &mdash; grey: collision meshes (coarse), orange: collision spheres, green: contact pads,
red: fingertip points (palm frame, metres)</p><div id="plot"></div>
<script>
const d = JSON.parse({data});
const v = d.vertices, f = d.faces, traces = [];
traces.push({{type: "mesh3d", x: v.map(p => p[0]), y: v.map(p => p[1]), z: v.map(p => p[2]),
  i: f.map(t => t[0]), j: f.map(t => t[1]), k: f.map(t => t[2]), color: "lightsteelblue", opacity: 0.5,
  name: "meshes"}});
const sx = [], sy = [], sz = [];
for (const [cx, cy, cz, r] of d.spheres) {{
  for (let a = 0; a <= 12; a++) for (let b = 0; b <= 6; b++) {{
    const u = 2 * Math.PI * a / 12, w = Math.PI * b / 6;
    sx.push(cx + r * Math.cos(u) * Math.sin(w)); sy.push(cy + r * Math.sin(u) * Math.sin(w));
    sz.push(cz + r * Math.cos(w));
  }}
  sx.push(null); sy.push(null); sz.push(null);
}}
traces.push({{type: "scatter3d", mode: "lines", x: sx, y: sy, z: sz, line: {{color: "orange", width: 1}},
  name: "spheres"}});
const p = d.pads, t = d.tips;
traces.push({{type: "scatter3d", mode: "markers", x: p.map(q => q[0]), y: p.map(q => q[1]), z: p.map(q => q[2]),
  marker: {{size: 2, color: "green"}}, name: "pads"}});
traces.push({{type: "scatter3d", mode: "markers", x: t.map(q => q[0]), y: t.map(q => q[1]), z: t.map(q => q[2]),
  marker: {{size: 6, color: "red"}}, name: "fingertips"}});
Plotly.newPlot("plot", traces, {{scene: {{aspectmode: "data"}}, margin: {{l: 0, r: 0, t: 0, b: 0}}}});
</script></body></html>
"""


def robot_page(name: str, preview: dict[str, Any], summary: str) -> str:
    """The HTML page of hand ``name`` from its preview (the JSON form of `manifoundation.contract.RobotPreview`)."""
    data = json.dumps(json.dumps(preview, separators=(",", ":"))).replace("</", "<\\/")
    return _PAGE.format(title=html.escape(name), summary=html.escape(summary), data=data)
