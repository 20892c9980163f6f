"""The terrain force limits as building blocks for your own CasADi problems.

Import this module to put the paper's force limits into an optimal-control problem of your
own (plain ``casadi.nlpsol``, ``casadi.Opti``, rockit, do-mpc, acados) or to generate C for
a vehicle computer. Nothing here writes a formula: every force is the expression of
:mod:`profileopt.physics.forces`, the same one the planner uses.

Terrain values
--------------
A force depends on the speed V (m/s) and on the terrain, given either as

* the roughness index RI (dimensionless; every model), or
* the worst-case elevation e_max (m) of Eq. (8), e_max = 4.7534 RI h for Pe = 0.999999
  (IECM, SBEM:EF and SBEM:TF; Prev:BEM is defined on the RI only).

Models: ``"prev_bem"``, ``"iecm"``, ``"sbem_ef"``, ``"sbem_tf"`` (default: SBEM:TF, the
force transmitted to the frame, held to ``vehicle.max_transmitted_force_n``).

What is here
------------
Forces on any kind of argument (numbers, numpy arrays, ``DM``, ``SX``, ``MX``)
    :func:`iecm_force_n`, :func:`sbem_ef_force_n`, :func:`sbem_tf_force_n` (speed, e_max),
    :func:`prev_bem_force_n` (speed, RI), and by model name
    :func:`~profileopt.physics.forces.force_n` (``ri=`` or ``e_max_m=``); :func:`force_limit_n`
    gives the limit.
Constraints over a horizon
    :func:`force_constraints` returns a :class:`ForceConstraints` that unpacks as the
    ``(g, lbg, ubg)`` triple of ``casadi.nlpsol``; :func:`add_force_constraints` adds the
    same to a ``casadi.Opti`` (or anything with a ``subject_to`` method, such as a rockit
    ``Ocp``). The normalised form g = F / F_limit - 1 <= 0 (default) is of order one,
    which IPOPT prefers to forces of thousands of newtons.
Between the grid points, on the terrain ahead (:mod:`profileopt.mpc.horizon`)
    :func:`terrain_envelope` turns a route into a smooth ``casadi.Function`` of the
    position, never below the e_max of any roughness window a stage can reach;
    :func:`interval_force_constraints` holds the limit over every speed between a stage's
    two speeds, the resonance peak included. Together they keep the limit between the grid
    points of any controller (``casadi.Opti``, ``nlpsol``, do-mpc's ``set_nl_cons``,
    rockit): see "Stages and segments" below. :func:`step_speed_envelope` gives SBEM:TF's
    step limit (steps met, drops landed) as a smooth speed cap of the position.
Named ``casadi.Function`` objects
    :func:`force_function` and :func:`constraint_function`, with named inputs and outputs,
    for ``map``, differentiation and code generation (:mod:`profileopt.mpc.codegen`);
    :func:`jacobian_function` gives their Jacobian with the same two inputs (CasADi's own
    ``fn.jacobian()`` wants the nominal output as a third).
Turns and hills (:mod:`profileopt.mpc.motion_constraints`)
    :func:`lateral_constraints` (v^2 |kappa| within the lateral and rollover limit),
    :func:`friction_constraints` (the friction circle) and :func:`power_constraints`
    (m (a + g sin theta) v <= P) return a :class:`MotionConstraints` that unpacks as
    ``(g, lbg, ubg)`` like :class:`ForceConstraints`, in the same *points* and *segments*
    layouts (below), for vehicles whose file gives the optional keys they need.
Resonance
    :func:`band_edges` (one band per terrain value, as speed bounds) and, re-exported,
    :func:`~profileopt.physics.speeds.speed_bands` (every band) and
    :func:`~profileopt.physics.speeds.allowable_speed`.

A minimal problem, fastest speeds over ten stages of varying roughness::

    import casadi as ca, numpy as np
    from .. import load_vehicle
    from .constraints import force_constraints
    vehicle = load_vehicle("atv")
    v = ca.SX.sym("v", 10)
    g, lbg, ubg = force_constraints(v, vehicle, ri=np.linspace(0.05, 0.4, 10))
    solver = ca.nlpsol("s", "ipopt", {"x": v, "f": -ca.sum1(v), "g": g})
    v_best = solver(x0=1, lbx=0, ubx=vehicle.max_speed_mps, lbg=lbg, ubg=ubg)["x"]

Stages and segments: which speeds a constraint covers
-----------------------------------------------------
``force_constraints(speed, vehicle, ri=terrain)`` (or ``e_max_m=terrain``) accepts two
layouts:

* *points*: N speeds and N terrain values (or one value for all): F(v_i, terrain_i) is
  constrained at each stage i;
* *segments*: N + 1 boundary speeds and N terrain values: segment i runs from speed v_i to
  v_{i+1} over terrain_i, and F(v_i, terrain_i) and F(v_{i+1}, terrain_i) are both
  constrained (2 N rows, ordered segment by segment).

Within a segment the vehicle passes through every speed between its entry and exit speeds
(docs/paper-notes.md, "Which root"), so the limit must hold over that whole interval, not
only at its ends. When the force grows monotonically with speed (IECM, SBEM:EF, Prev:BEM
always; SBEM:TF of a suspension with zeta >= 1 / (2 sqrt 2) such as the bundled ``atv``),
holding it at both ends holds it everywhere in between, and the *segments* layout is exact
for the terrain value given.

Two things the *segments* layout does not cover, and the helpers that do:

* **Resonance.** For a lightly damped suspension (SBEM:TF of ``atv-resonant``) the force
  peaks just above resonance, dips, then grows again: the admissible speeds over one
  terrain value form several *bands*, and a plan checked at the stage points can jump
  across a forbidden band between two stages. :func:`interval_force_constraints` adds the
  peak between the two speeds as a third row, so every speed passed through is held.
* **Terrain that depends on the predicted position.** A stage from s_k to s_k + ds meets
  every roughness window overlapping that stretch, not only the terrain at s_k.
  ``env = terrain_envelope(s, z, vehicle, reach_m=ds)`` is never below the largest e_max
  of those windows, and ``interval_force_constraints(v_k, v_k1, env(s_k), vehicle)`` then
  holds the limit for every speed driven inside every window the stage meets (the proof is
  in its docstring).

Band bounds remain useful as plain numbers: :func:`band_edges` gives per-stage bounds
(``"first"``: every speed from rest up to it is admissible; ``"largest"``: the top band,
for a vehicle already above resonance that stays there). A band whose lower edge is above
the current speed cannot be reached without crossing forbidden speeds on that terrain: that
is a planning decision (accelerate earlier, on smoother ground), not something one horizon
can fix; with :func:`interval_force_constraints` such a horizon is infeasible rather than
unsafe.

Units: speeds in m/s, e_max in m, forces in N, accelerations in m/s^2; RI and g are
dimensionless.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Literal

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from ..core.vehicle import Vehicle, require_vehicle
from ..errors import InputError
from ..physics.forces import (
    DEFAULT_MODEL,
    check_e_max_model,
    force_n,
    get_model,
    iecm_force_n,
    prev_bem_force_n,
    sbem_ef_force_n,
    sbem_tf_force_n,
)
from ..physics.speeds import SpeedBands, allowable_speed, speed_bands
from ..terrain.roughness import check_e_max, check_ri
from .functions import constraint_function, force_function, jacobian_function
from .horizon import (
    ForceConstraints,
    force_peak_ratio,
    interval_force_constraints,
    step_speed_envelope,
    terrain_envelope,
)
from .motion_constraints import (
    MotionConstraints,
    friction_constraints,
    lateral_constraints,
    power_constraints,
)

Band = Literal["first", "largest", "containing"]

__all__ = [
    "iecm_force_n",
    "sbem_ef_force_n",
    "sbem_tf_force_n",
    "prev_bem_force_n",
    "DEFAULT_MODEL",
    "force_n",
    "force_limit_n",
    "ForceConstraints",
    "force_constraints",
    "add_force_constraints",
    "MotionConstraints",
    "lateral_constraints",
    "friction_constraints",
    "power_constraints",
    "terrain_envelope",
    "step_speed_envelope",
    "interval_force_constraints",
    "force_peak_ratio",
    "force_function",
    "constraint_function",
    "jacobian_function",
    "BandEdges",
    "band_edges",
    "SpeedBands",
    "speed_bands",
    "allowable_speed",
]

def force_limit_n(vehicle: Vehicle, *, model: str = DEFAULT_MODEL) -> float:
    """The force limit (N) ``model`` is held to: ``max_transmitted_force_n`` for SBEM:TF,
    ``max_excitation_force_n`` for the other three.

    Parameters
    ----------
    vehicle : Vehicle
    model : str, default ``"sbem_tf"`` (:data:`~profileopt.physics.forces.DEFAULT_MODEL`)
    """
    return get_model(model).limit_n(vehicle)


# ---------------------------------------------------------------------------------------
# Constraints over a horizon
# ---------------------------------------------------------------------------------------


def _column(x: Any) -> Any:
    """``x`` as a column: SX/MX unchanged (reshaped), numbers and arrays as DM."""
    if isinstance(x, (ca.SX, ca.MX)):
        return ca.vec(x)
    if isinstance(x, ca.DM):
        return ca.vec(x)
    arr = np.asarray(x, dtype=float)
    return ca.DM(arr.reshape(-1, 1))


def _pair_stages(speed: Any, terrain: Any, where: str) -> tuple[Any, Any]:
    """Speeds and terrain values row by row for the points or segments layout."""
    n_v, n_t = speed.shape[0], terrain.shape[0]
    if n_t == 1 and n_v >= 1:
        return speed, ca.repmat(terrain, n_v, 1)
    if n_v == n_t:
        return speed, terrain
    if n_v == n_t + 1:
        # segments: both ends of segment i against terrain i, ordered segment by segment
        starts, ends = speed[:-1], speed[1:]
        v_rows = ca.vec(ca.horzcat(starts, ends).T)
        t_rows = ca.vec(ca.horzcat(terrain, terrain).T)
        return v_rows, t_rows
    raise InputError(
        f"{where}: {n_v} speeds and {n_t} terrain values do not match; give N speeds and N "
        "values (points), N + 1 speeds and N values (segments), or one terrain value"
    )


def force_constraints(
    speed_mps: Any,
    vehicle: Vehicle,
    *,
    ri: Any = None,
    e_max_m: Any = None,
    model: str = DEFAULT_MODEL,
    normalised: bool = True,
    accel_mps2: Any = None,
) -> ForceConstraints:
    """The force limit over a horizon of speed symbols, as lbg <= g <= ubg.

    Parameters
    ----------
    speed_mps : casadi.SX or casadi.MX, shape (N,) or (N + 1,)
        Stage speeds (m/s). Numbers and arrays work too (g is then a DM).
    vehicle : Vehicle
    ri : SX, MX, DM, numpy array or number, shape (N,) or scalar, optional
        Roughness index of each stage or segment (dimensionless, >= 0): parameters or
        numbers. Give exactly one of ``ri`` and ``e_max_m``.
    e_max_m : SX, MX, DM, numpy array or number, shape (N,) or scalar, optional
        Worst-case elevation (m) of each stage or segment instead of ``ri`` (IECM, SBEM:EF,
        SBEM:TF only).
    model : str, default ``"sbem_tf"`` (:data:`~profileopt.physics.forces.DEFAULT_MODEL`)
        ``"prev_bem"``, ``"iecm"``, ``"sbem_ef"`` or ``"sbem_tf"``.
    normalised : bool, default True
        Force rows g = F / F_limit - 1 <= 0 (dimensionless, well scaled for IPOPT) if True,
        g = F <= F_limit (N) if False.
    accel_mps2 : SX or MX, shape (M,), optional
        Accelerations (m/s^2) to bound by [-max_decel_mps2, max_accel_mps2]; appended after
        the force rows.

    Returns
    -------
    ForceConstraints
        Unpacks as ``g, lbg, ubg``. Layouts (module docstring): N speeds and N terrain
        values give N force rows (points); N + 1 speeds and N values give 2 N rows, the
        entry and exit speed of each segment against its terrain (segments); one terrain
        value applies to every speed.

    Raises
    ------
    InputError
        Unknown model, both or neither of ``ri`` and ``e_max_m``, Prev:BEM with
        ``e_max_m``, mismatched lengths, or a negative or NaN terrain value.
    """
    spec = get_model(model)
    if (ri is None) == (e_max_m is None):
        raise InputError("force_constraints: give exactly one of ri (roughness index) and e_max_m (metres)")
    if isinstance(e_max_m, Vehicle) or isinstance(ri, Vehicle):
        raise InputError("force_constraints: e_max_m or ri is a Vehicle: give (speed_mps, vehicle, e_max_m=...) "
                         "or ri=...")
    vehicle = require_vehicle(vehicle, "force_constraints")
    terrain = "ri" if e_max_m is None else "e_max"
    if terrain == "e_max":
        check_e_max_model(model)
    value = ri if terrain == "ri" else e_max_m
    try:
        (check_ri if terrain == "ri" else check_e_max)(value)
    except InputError as exc:
        raise InputError(f"force_constraints: {exc}") from None
    speed_col = _column(speed_mps)
    value_col = _column(value)
    if speed_col.shape[0] == 0:
        raise InputError("force_constraints: no speeds were given; pass at least one stage speed")
    v_rows, t_rows = _pair_stages(speed_col, value_col, "force_constraints")
    force = force_n(v_rows, vehicle, model=model, **{"ri" if terrain == "ri" else "e_max_m": t_rows})
    limit = spec.limit_n(vehicle)
    n = int(force.shape[0])
    if normalised:
        g_force = force / limit - 1.0
        upper = np.zeros(n)
    else:
        g_force = force
        upper = np.full(n, limit)
    lbg, ubg = [np.full(n, -np.inf)], [upper]
    rows = [g_force]
    if accel_mps2 is not None:
        a = _column(accel_mps2)
        rows.append(a)
        lbg.append(np.full(a.shape[0], -vehicle.max_decel_mps2))
        ubg.append(np.full(a.shape[0], vehicle.max_accel_mps2))
    return ForceConstraints(
        g=ca.vertcat(*rows),
        lbg=np.concatenate(lbg),
        ubg=np.concatenate(ubg),
        force_n=force,
        limit_n=limit,
        n_force=n,
        model=model,
        normalised=normalised,
    )


def add_force_constraints(
    problem: Any,
    speed_mps: Any,
    vehicle: Vehicle,
    *,
    ri: Any = None,
    e_max_m: Any = None,
    model: str = DEFAULT_MODEL,
    normalised: bool = True,
    accel_mps2: Any = None,
) -> ForceConstraints:
    """Add the force limit (and acceleration bounds) of :func:`force_constraints` to ``problem``.

    Parameters
    ----------
    problem : casadi.Opti or any object with a ``subject_to`` method
        The problem to add the constraints to (``casadi.Opti``, a rockit ``Ocp``, ...).
    speed_mps : casadi.MX, shape (N,) or (N + 1,)
        Stage speeds (m/s): ``opti.variable`` entries or expressions of them.
    vehicle : Vehicle
    ri, e_max_m : exactly one of them
        Roughness index (dimensionless) or worst-case elevation (m) per stage or segment:
        ``opti.parameter`` (set with ``opti.set_value`` before each solve) or numbers.
    model, normalised, accel_mps2
        As for :func:`force_constraints`.

    Returns
    -------
    ForceConstraints
        What was added: the force rows as ``g[:n_force] <= ubg[:n_force]``, the acceleration
        rows as ``casadi.Opti.bounded(lbg, a, ubg)``.
    """
    if not callable(getattr(problem, "subject_to", None)):
        raise InputError(
            f"add_force_constraints: problem must have a subject_to method (e.g. a casadi.Opti), "
            f"got {type(problem).__name__}"
        )
    cons = force_constraints(
        speed_mps, vehicle, ri=ri, e_max_m=e_max_m, model=model, normalised=normalised, accel_mps2=accel_mps2
    )
    n = cons.n_force
    problem.subject_to(cons.g[:n] <= ca.DM(cons.ubg[:n]))
    if cons.g.shape[0] > n:
        problem.subject_to(ca.Opti.bounded(ca.DM(cons.lbg[n:]), cons.g[n:], ca.DM(cons.ubg[n:])))
    return cons


# ---------------------------------------------------------------------------------------
# Resonance: the band a controller should stay in
# ---------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class BandEdges:
    """One admissible speed band per terrain value, as bounds for stage speeds.

    Attributes
    ----------
    lower_mps, upper_mps : numpy.ndarray, shape of ``ri``
        The band [lower, upper] (m/s): every speed in it keeps the force within the limit.
        Both 0 when the terrain admits no speed at all (for ``"first"`` and ``"largest"``:
        even the static force exceeds the limit, the vehicle must not be there); NaN for
        ``"containing"`` when the given speed lies in no band.
    band : str
        Which band: ``"first"``, ``"largest"`` or ``"containing"``.
    """

    lower_mps: np.ndarray
    upper_mps: np.ndarray
    band: str


def band_edges(
    ri: ArrayLike,
    vehicle: Vehicle,
    *,
    model: str = DEFAULT_MODEL,
    band: Band = "first",
    speed_mps: ArrayLike | None = None,
) -> BandEdges:
    """Edges of the admissible speed band to pin each stage to (see "Stages and segments"
    in the module docstring).

    Parameters
    ----------
    ri : array_like, any shape
        Roughness index of each stage (dimensionless, >= 0).
    vehicle : Vehicle
    model : str, default ``"sbem_tf"`` (:data:`~profileopt.physics.forces.DEFAULT_MODEL`)
    band : {"first", "largest", "containing"}, default ``"first"``
        ``"first"``: [0, V_first], safe from rest and for any speed path below V_first.
        ``"largest"``: the top band, only for a vehicle already above resonance that stays
        there. ``"containing"``: the band that contains ``speed_mps`` (the current speed), to
        keep a vehicle in the band it is in. ``"all"`` is refused: one band per terrain
        value is given here, :func:`~profileopt.physics.speeds.speed_bands` gives every band.
    speed_mps : array_like, broadcast against ``ri``, optional
        Required for ``"containing"`` (m/s).

    Returns
    -------
    BandEdges
        Bounds (m/s) of the shape of ``ri``. Every band of every RI:
        :func:`~profileopt.physics.speeds.speed_bands`.

    Raises
    ------
    InputError
        Unknown ``model`` or ``band``, ``band="all"``, a NaN or negative ``ri``, or
        ``band="containing"`` without ``speed_mps``.
    """
    get_model(model)
    if band == "all":
        raise InputError("band_edges: band 'all' means every band; use speed_bands(ri, vehicle) for every band, "
                         "or choose band 'first', 'largest' or 'containing'")
    if band not in ("first", "largest", "containing"):
        raise InputError(f"band_edges: band {band!r} is unknown; choose 'first', 'largest' or 'containing'")
    values = np.asarray(ri, dtype=float)
    try:
        bands = speed_bands(values.ravel(), vehicle, model=model)
    except InputError as exc:
        raise InputError(f"band_edges: {exc}") from None
    n = values.size
    if band == "first":
        lower, upper = np.zeros(n), bands.first()
    elif band == "largest":
        last = np.maximum(bands.count - 1, 0)
        rows = np.arange(n)
        has = bands.count > 0
        lower = np.where(has, bands.lower_mps[rows, last], 0.0)
        upper = np.where(has, bands.upper_mps[rows, last], 0.0)
    else:
        if speed_mps is None:
            raise InputError("band_edges: band='containing' needs speed_mps, the speed to find the band of")
        v = np.broadcast_to(np.asarray(speed_mps, dtype=float), values.shape).ravel()
        inside = (bands.lower_mps <= v[:, None]) & (v[:, None] <= bands.upper_mps)
        found = inside.any(axis=1)
        j = np.argmax(inside, axis=1)
        rows = np.arange(n)
        lower = np.where(found, bands.lower_mps[rows, j], math.nan)
        upper = np.where(found, bands.upper_mps[rows, j], math.nan)
    return BandEdges(lower.reshape(values.shape), upper.reshape(values.shape), band)
