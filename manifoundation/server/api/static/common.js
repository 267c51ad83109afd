// Shared by the dashboard and the viewer: the API key from the URL fragment (#key=...), never sent to a server
// by the browser, added as a bearer header to every data request.
"use strict";
const mani = (() => {
  const params = new URLSearchParams(window.location.hash.slice(1));
  const key = params.get("key");
  const suffix = key ? "#key=" + encodeURIComponent(key) : "";
  async function fetchJson(url) {
    const headers = { Accept: "application/json" };
    if (key) headers.Authorization = "Bearer " + key;
    const response = await fetch(url, { headers, cache: "no-store" });
    const body = await response.json().catch(() => ({}));
    if (!response.ok) throw new Error((body && body.error) || response.status + " " + response.statusText);
    return body;
  }
  function text(value) { return value === null || value === undefined ? "" : String(value); }
  function cell(row, value, cls) {
    const td = document.createElement("td");
    if (value instanceof Node) td.appendChild(value); else td.textContent = text(value);
    if (cls) td.className = cls;
    row.appendChild(td);
    return td;
  }
  function seconds(s) {
    if (s === null || s === undefined) return "–";
    return s < 1 ? (s * 1000).toFixed(0) + " ms" : s.toFixed(2) + " s";
  }
  function clock(t) { return t ? new Date(t * 1000).toLocaleTimeString() : ""; }
  return { fetchJson, cell, seconds, clock, suffix, text };
})();
