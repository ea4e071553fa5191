"""The hand on the bench: the hardware interface a user implements for their driver, a loopback for tests, and
the MuJoCo stand-in with a real hand's effects (its truth hidden) that the tests and benchmarks drive.

Everything that must run on the hand goes through :class:`HardwareInterface`.
"""

from .effects import PlantEffects, real_hand_effects
from .interface import HardwareInterface, Loopback, Reading, check_command
from .mujoco_hand import MujocoHand
from .play import play

__all__ = ["HardwareInterface", "Loopback", "Reading", "check_command", "MujocoHand", "PlantEffects",
           "real_hand_effects", "play"]
