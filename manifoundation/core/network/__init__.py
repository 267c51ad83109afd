"""The ManiFoundation network (paper §III-A): CVAE contact heatmaps and force/motion maps, contact selection.

Pure science: arrays and tensors in, dataclasses out. Importing this package imports torch.

Modules: ``config`` (registry), ``point_ops`` / ``hierarchy`` / ``layers`` (PointNet++ parts), ``properties``
(ψ_i and masked mean pooling), ``encoders`` and ``model`` (the CVAE), ``loss`` (Eq. 3), ``normalize`` and
``resample`` (request frame ↔ model frame), ``inference`` (:class:`ContactPredictor`), ``selection`` (NMS),
``checkpoint`` (safetensors + model card).
"""

from manifoundation.core.errors import CheckpointError
from manifoundation.core.network.checkpoint import ModelCard, load_checkpoint, save_checkpoint
from manifoundation.core.network.config import LevelConfig, NetworkConfig, get_config, list_configs, register_config
from manifoundation.core.network.inference import ContactPredictor, NetworkInput, NetworkOutput
from manifoundation.core.network.loss import cvae_loss
from manifoundation.core.network.model import ManiFoundationNet, ObjectTensors, count_parameters, create_model
from manifoundation.core.network.normalize import Normalizer
from manifoundation.core.network.properties import PROPERTY_NAMES
from manifoundation.core.network.selection import ContactSelection, select_contacts

__all__ = [
    "PROPERTY_NAMES",
    "CheckpointError",
    "ContactPredictor",
    "ContactSelection",
    "LevelConfig",
    "ManiFoundationNet",
    "ModelCard",
    "NetworkConfig",
    "NetworkInput",
    "NetworkOutput",
    "Normalizer",
    "ObjectTensors",
    "count_parameters",
    "create_model",
    "cvae_loss",
    "get_config",
    "list_configs",
    "load_checkpoint",
    "register_config",
    "save_checkpoint",
    "select_contacts",
]
