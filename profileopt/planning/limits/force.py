"""The terrain force limit: the chosen model's admissible speed bands of each segment.

Each segment meets several roughness windows; its bands are the speeds whose predicted
force is within the vehicle's limit for the RI of every one of them
(:func:`profileopt.physics.speeds.speed_bands_of_sets`), exactly.
A resonant vehicle may have several bands; the planner keeps both boundary speeds of a
segment in one of them, so the limit holds for every speed driven in between.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from ...physics.forces import DEFAULT_MODEL, get_model
from ...physics.speeds import SpeedBands, max_force_of_sets, speed_bands_of_sets
from .base import Limit, PlanContext

if TYPE_CHECKING:
    from ...core.profile import Profile

__all__ = ["ForceLimit"]


@dataclasses.dataclass(frozen=True)
class ForceLimit(Limit):
    """The predicted terrain force of ``model`` within the vehicle's limit, at every speed.

    Attributes
    ----------
    model : str
        Force model key (``"sbem_tf"``, ``"sbem_ef"``, ``"iecm"``, ``"prev_bem"``).
    """

    model: str = DEFAULT_MODEL
    name = "force"
    binding = "force"
    #: The last call's distinct RIs and their bands (:class:`~profileopt.physics.speeds.BandMemo`):
    #: a refined plan asks again for every segment it kept whole.
    _memo: list = dataclasses.field(default_factory=list, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        get_model(self.model)  # an unknown model is refused here, by name

    def speed_bands(self, context: PlanContext) -> SpeedBands:
        """Every speed band of each segment admissible for every window it meets (m/s).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        SpeedBands
        """
        segments = context.segments
        first, stop = segments.window_ranges()
        bands, memo = speed_bands_of_sets(segments.windows.ri, first, stop, context.vehicle, model=self.model,
                                          memo=self._memo[0] if self._memo else None)
        self._memo[:] = [memo]
        return bands

    def predicted_force_n(self, context: PlanContext, speed_mps: np.ndarray) -> np.ndarray:
        """The largest predicted force over each segment's speeds and the windows it meets (N).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.
        speed_mps : numpy.ndarray, shape (N+1,)
            Speeds at the segment boundaries (m/s).

        Returns
        -------
        numpy.ndarray, shape (N,)
        """
        segments = context.segments
        first, stop = segments.window_ranges()
        return max_force_of_sets(segments.windows.ri, first, stop, speed_mps, context.vehicle, model=self.model,
                                 memo=self._memo[0] if self._memo else None)

    def check(self, profile: "Profile") -> float:
        """How far the largest predicted force inside any segment exceeds the limit (relative).

        Parameters
        ----------
        profile : Profile
            The profile about to be returned.

        Returns
        -------
        float
        """
        return max(float(np.max(profile.force_n / profile.force_limit_n)) - 1.0, 0.0)

    def margins(self, profile: "Profile") -> dict[str, dict]:
        """The largest predicted force over its limit, and where.

        Parameters
        ----------
        profile : Profile
            A planned profile.

        Returns
        -------
        dict
            ``{"force": {"ratio": float, "s_m": float}}``.
        """
        ratio = profile.force_n[:-1] / profile.force_limit_n[:-1]
        k = int(np.argmax(ratio))
        return {"force": {"ratio": float(ratio[k]), "s_m": float(profile.s_m[k])}}

    def band_reason(self, profile: "Profile", segment: int) -> str:
        """The model, its limit and the segment's RI; and whether a faster band was out of reach.

        Parameters
        ----------
        profile : Profile
            A planned profile.
        segment : int
            Index of the segment.

        Returns
        -------
        str
        """
        i = segment
        spec = get_model(profile.model)
        tol = 1e-6 * max(float(profile.speed_mps.max()), 1.0)
        reason = (f"the {spec.label} force limit ({spec.quantity}, {profile.force_limit_n[i]:g} N) "
                  f"at RI {profile.ri[i]:.3f}")
        largest = profile.allowable_largest_mps
        if largest is not None and profile.band_upper_mps[i] < largest[i] - tol:
            reason += (f", held below resonance: the faster band up to {largest[i]:.3g} m/s "
                       "cannot be entered or left in time")
        return reason
