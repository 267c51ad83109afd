"""The server: the API front ends (`api`: HTTP, gRPC, MCP), the job queue (`queue`) and the worker (`worker`).

`api` never imports torch or the science (`manifoundation.core`); the worker runs the science in its own processes.
"""
