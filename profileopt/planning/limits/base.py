"""The one small protocol every kind of limit on a speed profile follows.

A limit contributes to a plan in up to four ways, each a method of :class:`Limit` that
returns ``None`` (or the neutral value) when the limit has nothing to say:

- admissible speeds of each segment, as *bands* (:meth:`Limit.speed_bands`; at most one
  limit of a plan, the force model's) or as a *cap* (:meth:`Limit.speed_cap_mps`). They
  hold for every speed driven inside the segment, so they become bounds on the squared
  speed b = v^2 at the segment's two boundaries;
- acceleration bounds of each segment (:meth:`Limit.accel_bounds_mps2`), rows of the NLP
  and slopes of the exact forward-backward pass;
- a jerk bound (:meth:`Limit.jerk_bound_mps3`), rows of the NLP at interior boundaries;
- a drive power limit (:meth:`Limit.drive_power`), kept exactly by the forward pass, and
  rows of the NLP on each segment's two squared speeds (:meth:`Limit.nlp_rows`, a family
  of :data:`profileopt.physics.rows.ROW_FAMILIES`) where the bounds above do not imply it;
- the name of what holds the speed, for the profile's ``binding`` column
  (:attr:`Limit.binding`, :meth:`Limit.cap_binding`), and where along the route a cap is
  set (:meth:`Limit.cap_stretches_m`, so that refining can keep it off the rest of a segment);
- the independent checks: of the NLP solver's solution before it is used
  (:meth:`Limit.violation`) and of the finished profile (:meth:`Limit.check`), and its
  margins for the summary (:meth:`Limit.margins`).

Adding a kind of limit is one new module with a subclass, plus its registration in
:func:`profileopt.planning.limits.default_limits` (or, for a limit of your own, passing it
to :func:`profileopt.plan` as ``extra_limits=``).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from ...core.path import SegmentPath, flat_path
from ..nlp.problem import family_rows

if TYPE_CHECKING:
    from ...core.profile import Profile
    from ...core.route import Route
    from ...core.segments import Segments
    from ...core.vehicle import Vehicle
    from ...physics.speeds import SpeedBands
    from ..bands import DrivePower

__all__ = ["PlanContext", "Limit", "RowLimit", "worst_ratio", "own_cap_excess"]


@dataclasses.dataclass(frozen=True, eq=False)
class PlanContext:
    """What the limits of one plan see.

    Attributes
    ----------
    route : Route
        The terrain samples (and speed limits) of the route.
    vehicle : Vehicle
        The vehicle planned for.
    segments : Segments
        The route cut into segments (N of them), with each segment's samples and roughness.
    path : SegmentPath, optional
        Each segment's turns and slopes; None: a straight, level route.
    """

    route: "Route"
    vehicle: "Vehicle"
    segments: "Segments"
    path: SegmentPath | None = None

    @property
    def turns_and_slopes(self) -> SegmentPath:
        """:attr:`path`, or a straight level path when there is none."""
        return self.path if self.path is not None else flat_path(self.segments.count)


class Limit:
    """One kind of limit on a speed profile; the base class contributes nothing.

    Subclasses override the methods for what they limit. Every array is per segment, shape
    (N,), or per boundary, shape (N+1,), of ``context.segments``.
    """

    #: Short name, used in summaries and messages.
    name: str = "limit"
    #: What the ``binding`` column says where this limit holds the speed (its cap, its
    #: acceleration bounds or its rows): one of ``force``, ``speed_limit``, ``top_speed``,
    #: ``lateral``, ``friction``, ``accel``, ``power``, ``jerk``.
    binding: str = "limit"

    def speed_bands(self, context: PlanContext) -> "SpeedBands | None":
        """The admissible speed bands of each segment (m/s), or None.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        SpeedBands or None
        """
        return None

    def predicted_force_n(self, context: PlanContext, speed_mps: np.ndarray) -> np.ndarray | None:
        """The largest force the limit's model predicts over each segment's speeds (N), or None.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.
        speed_mps : numpy.ndarray, shape (N+1,)
            Speeds at the segment boundaries (m/s).

        Returns
        -------
        numpy.ndarray, shape (N,), or None
        """
        return None

    def speed_cap_mps(self, context: PlanContext) -> np.ndarray | None:
        """A cap on every speed driven inside each segment (m/s), shape (N,), or None.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        numpy.ndarray or None
        """
        return None

    def accel_bounds_mps2(self, context: PlanContext) -> tuple[np.ndarray, np.ndarray] | None:
        """Deceleration (a positive number) and acceleration bounds of each segment (m/s^2).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        (decel_mps2, accel_mps2) : tuple of numpy.ndarray, shape (N,), or None
        """
        return None

    def cap_binding(self, context: PlanContext, cap_mps: np.ndarray) -> np.ndarray:
        """The ``binding`` name of this limit's cap in each segment, shape (N,).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.
        cap_mps : numpy.ndarray, shape (N,)
            This limit's caps (m/s).

        Returns
        -------
        numpy.ndarray of str
        """
        return np.full(cap_mps.shape, self.binding, dtype=object)

    def cap_stretches_m(self, context: PlanContext) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Where along the route this limit's cap is set, as stretches with their caps, or None.

        A cap holds every segment that shares a point with a stretch; where the plan meets
        it, the refine round (``plan(refine=True)``) cuts such a segment at the samples
        just outside the stretch that sets its cap, so that only the piece meeting it keeps
        the cap. A limit whose cap is a property of the whole segment (a turn's, the top
        speed) returns None.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        (start_m, end_m, cap_mps) : tuple of numpy.ndarray, shape (R,), or None
            Each stretch's ends along the route (m), start_m <= end_m, and its cap (m/s).
        """
        return None

    def drive_power(self, context: PlanContext) -> "DrivePower | None":
        """The drive power limit of the forward pass, or None (at most one limit gives one).

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        DrivePower or None
        """
        return None

    def nlp_rows(self, context: PlanContext, cap_mps: np.ndarray, decel_mps2: np.ndarray,
                 accel_mps2: np.ndarray) -> tuple[str, np.ndarray] | None:
        """Rows this limit needs in the NLP, given every limit's caps and acceleration bounds.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.
        cap_mps : numpy.ndarray, shape (N,)
            The lowest cap of each segment (m/s).
        decel_mps2, accel_mps2 : numpy.ndarray, shape (N,)
            The tightest acceleration bounds of each segment (m/s^2).

        Returns
        -------
        (family, data) or None
            A key of :data:`profileopt.physics.rows.ROW_FAMILIES` and its data, shape
            (N, D); None when the caps and bounds already imply the limit in every segment.
        """
        return None

    def inner_bounds(self, context: PlanContext, cap_mps: np.ndarray, decel_mps2: np.ndarray,
                     accel_mps2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Caps and acceleration bounds tight enough to keep this limit's NLP rows without them.

        Used by the fallback profile when the NLP cannot be solved: the forward-backward profile within
        these keeps every row.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.
        cap_mps : numpy.ndarray, shape (N,)
            The caps (m/s).
        decel_mps2, accel_mps2 : numpy.ndarray, shape (N,)
            The acceleration bounds (m/s^2).

        Returns
        -------
        (cap_mps, decel_mps2, accel_mps2) or None
            Tightened copies; None when this limit has no NLP rows.
        """
        return None

    def jerk_bound_mps3(self, context: PlanContext) -> float:
        """Bound on |jerk| = |v da/ds| at the interior boundaries (m/s^3); inf for none.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.

        Returns
        -------
        float
        """
        return math.inf

    def violation(self, context: PlanContext, b: np.ndarray) -> float:
        """Largest relative violation of this limit's NLP rows by squared speeds ``b``.

        Checked on the NLP solver's solution before it is used: above the plan's ``check_rtol`` the
        solution is replaced by the fallback profile.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.
        b : numpy.ndarray, shape (N+1,)
            Squared speeds at the boundaries (m^2/s^2).

        Returns
        -------
        float
            0 when the limit holds.
        """
        return 0.0

    def check(self, profile: "Profile") -> float:
        """Largest relative violation of this limit by a finished profile (0 if none).

        The planner never returns a profile for which this exceeds its ``check_rtol``.

        Parameters
        ----------
        profile : Profile
            The profile about to be returned.

        Returns
        -------
        float
        """
        return 0.0

    def margins(self, profile: "Profile") -> dict[str, dict]:
        """The tightest ratio of each constrained quantity to its limit, and where.

        Parameters
        ----------
        profile : Profile
            A planned profile.

        Returns
        -------
        dict
            ``{quantity: {"ratio": float or None, "s_m": float or None}}``; None where the
            limit is off or never used.
        """
        return {}

    def cap_reason(self, profile: "Profile", segment: int) -> str:
        """Why segment ``segment``'s speed is held at this limit's cap, for the summary.

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
        return f"the {self.name} limit ({profile.speed_cap_mps[segment]:.3g} m/s)"

    def band_reason(self, profile: "Profile", segment: int) -> str:
        """Why segment ``segment``'s speed is held at the top of its band, for the summary.

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
        return f"the {self.name} limit"


class RowLimit(Limit):
    """A limit that a family of NLP rows keeps on each segment's two squared speeds
    (:data:`profileopt.physics.rows.ROW_FAMILIES`), where it can bind.

    The family's expressions are evaluated once for every use: on the NLP solver's solution
    (:meth:`violation`), and on a finished profile at its exact speeds (:meth:`row_values`,
    for :meth:`check` and a subclass's :meth:`margins`). A subclass names its ``family`` and
    gives its per-segment data (:meth:`row_data`).
    """

    #: The key of :data:`profileopt.physics.rows.ROW_FAMILIES` of this limit's rows.
    family: str = ""

    def row_data(self, path: SegmentPath) -> np.ndarray:
        """The family's data of each segment, shape (N, D), columns as ROW_FAMILIES names them.

        Parameters
        ----------
        path : SegmentPath
            Each segment's turns and slopes.

        Returns
        -------
        numpy.ndarray
        """
        raise NotImplementedError

    def violation(self, context: PlanContext, b: np.ndarray) -> float:
        """Largest row over 1, minus 1 (0 when the limit holds), as the NLP's rows see it.

        Parameters
        ----------
        context : PlanContext
            The route, vehicle and segments of the plan.
        b : numpy.ndarray, shape (N+1,)
            Squared speeds at the boundaries (m^2/s^2).

        Returns
        -------
        float
        """
        rows = family_rows(self.family, b, context.segments.length_m, self.row_data(context.turns_and_slopes))
        return max(float(rows.max()) - 1.0, 0.0)

    def row_values(self, profile: "Profile") -> np.ndarray:
        """The largest of the family's rows in each segment of a profile, at its exact speeds
        (<= 1 where the limit holds), shape (N,).

        Parameters
        ----------
        profile : Profile
            A planned profile.

        Returns
        -------
        numpy.ndarray
        """
        n = profile.s_m.size - 1
        path = profile.path if profile.path is not None else flat_path(n)
        return family_rows(self.family, profile.speed_mps**2, np.diff(profile.s_m), self.row_data(path),
                           smooth=False).max(axis=0)

    def check(self, profile: "Profile") -> float:
        """How far the family's largest row in any segment exceeds 1 (its rows are the
        limited quantity over its limit: the friction usage, the drive power over P).

        Parameters
        ----------
        profile : Profile
            The profile about to be returned.

        Returns
        -------
        float
        """
        return max(float(np.max(self.row_values(profile), initial=0.0)) - 1.0, 0.0)


def worst_ratio(values: np.ndarray, limit: float, where: np.ndarray) -> dict:
    """The largest ``values / limit`` and its position, or None where the limit is off or
    never used (no positive value).

    Parameters
    ----------
    values : numpy.ndarray, shape (K,)
        The constrained quantity.
    limit : float
        Its limit (inf: off).
    where : numpy.ndarray, shape (K,)
        Position of each value (m).

    Returns
    -------
    dict
        ``{"ratio": float or None, "s_m": float or None}``.
    """
    if values.size == 0 or not math.isfinite(limit) or values.max() <= 0:
        return {"ratio": None, "s_m": None}
    k = int(np.argmax(values))
    return {"ratio": float(values[k] / limit), "s_m": float(where[k])}


def own_cap_excess(limit: Limit, profile: "Profile") -> float:
    """How far a speed in a segment whose cap ``limit`` sets exceeds that cap (relative, 0 if
    none): the :meth:`Limit.check` of a limit that only caps speeds over stretches.

    Parameters
    ----------
    limit : Limit
        One of ``profile.limits``.
    profile : Profile
        The profile about to be returned.

    Returns
    -------
    float
    """
    mine = [k for k, other in enumerate(profile.limits) if other is limit]
    if not mine or profile.cap_source is None:
        return 0.0
    where = np.flatnonzero(profile.cap_source == mine[0])
    if where.size == 0:
        return 0.0
    top = np.maximum(profile.speed_mps[where], profile.speed_mps[where + 1])
    return max(float(np.max(top / profile.speed_cap_mps[where])) - 1.0, 0.0)
