"""The Python SDK, the `mani` command line and the wire contract. Never imports torch or server code."""
