"""The science entry point the workers call: `run_pipeline` / `run_pipeline_batch` on `SynthesisInput`.

Pure: numpy arrays and a `manifoundation.core.robots.Hand` in, dataclasses out; never imports clients, service or
workers.
"""

from manifoundation.core.pipeline.run import run_pipeline, run_pipeline_batch
from manifoundation.core.pipeline.types import (
    Cancelled,
    InvalidInput,
    IterationOutput,
    JointInput,
    ModelUnavailable,
    PhysicsMode,
    ProposalOutput,
    QualityOutput,
    SynthesisInput,
    SynthesisOutput,
    TaskInput,
    physics_mode,
)

__all__ = [
    "Cancelled",
    "InvalidInput",
    "IterationOutput",
    "JointInput",
    "ModelUnavailable",
    "PhysicsMode",
    "ProposalOutput",
    "QualityOutput",
    "SynthesisInput",
    "SynthesisOutput",
    "TaskInput",
    "physics_mode",
    "run_pipeline",
    "run_pipeline_batch",
]
