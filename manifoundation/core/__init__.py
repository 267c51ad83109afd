"""The science: hands, geometry, network, refinement, data and training.

Pure: arrays in, dataclasses out. Never imports `service`, `workers`, `clients`, FastAPI, Redis or settings.
"""
