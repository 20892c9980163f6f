"""Online speed selection: the speed every cycle from the terrain sensed ahead.

- :mod:`.sensed`: the terrain measured so far, and where measurement stops;
- :mod:`.selector`: :class:`SpeedSelector`, the per-cycle command with a plan over the sensed
  horizon that never relies on terrain not yet measured being better than assumed;
- :mod:`.drive`: :func:`drive`, a closed-loop run over a route revealed only within the
  sensing range, judged by the exact simulation (``profileopt drive``).
"""

from .drive import Drive, drive
from .selector import Command, SpeedSelector, unseen_speed_mps
from .sensed import SensedTerrain

__all__ = ["SpeedSelector", "Command", "SensedTerrain", "unseen_speed_mps", "Drive", "drive"]
