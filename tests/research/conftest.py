"""The science fixtures (a box, the Panda gripper, a LEAP hand on a cube): tests/science_fixtures.py."""

from tests.science_fixtures import box, gripper, leap_on_a_box

__all__ = ["box", "gripper", "leap_on_a_box"]
