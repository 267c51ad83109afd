"""Queue backends (torch-free) and worker processes (which load `models` in the worker process only)."""
