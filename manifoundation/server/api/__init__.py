"""The HTTP service (FastAPI). Never imports torch or `models`."""
