"""Robot hands: kinematics with a floating palm, collision spheres, surface samples (see `hand.py`, `registry.py`)."""

from models.errors import HandLoadError, UnknownHand
from models.robots.hand import Hand
from models.robots.registry import get_hand, list_hands, load_hand

__all__ = ["Hand", "HandLoadError", "UnknownHand", "get_hand", "list_hands", "load_hand"]
