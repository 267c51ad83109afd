"""MCP tools for LLM agents (the official ``mcp`` SDK): mounted on the service at ``/mcp`` (streamable HTTP) and
served over stdio by ``mani mcp``. Modules: `tools` (the tool server), `backend` (the service's submission path or
the SDK), `objects` (uploaded objects per tenant), `shapes` (primitive objects), `summaries` (what tools answer),
`endpoint` (the ``/mcp`` route, started on first use), `http` (the mounted server), `cli` (``mani mcp``)."""
