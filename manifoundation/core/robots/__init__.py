"""Robot hands: kinematics with a floating palm, collision spheres, surface samples (see `hand.py`, `registry.py`)."""

from manifoundation.core.errors import HandLoadError, UnknownHand
from manifoundation.core.robots.hand import Hand
from manifoundation.core.robots.registry import get_hand, list_hands, load_hand

__all__ = ["Hand", "HandLoadError", "UnknownHand", "get_hand", "list_hands", "load_hand"]
