"""The force limits as named ``casadi.Function`` objects, with the vehicle folded in.

:func:`force_function` (the model's force) and :func:`constraint_function` (g <= 0 when the
force is within the limit) take the stage speeds and the terrain (roughness index or
worst-case elevation) and are what :mod:`profileopt.mpc.codegen` generates as C;
:func:`jacobian_function` gives their Jacobians with the same inputs. They evaluate the very
expressions of :mod:`profileopt.physics.forces`. Also importable from :mod:`profileopt.mpc.constraints`.
A negative or NaN terrain value is not terrain: every Function returns NaN there, never a
force or a g <= 0 that would call it admissible (and so does the generated C).
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any, Literal

import casadi as ca

from ..core.vehicle import Vehicle
from ..errors import InputError
from ..physics.forces import DEFAULT_MODEL, FORCE_OF_E_MAX, force_n, get_model
from .horizon import interval_force_constraints

__all__ = ["force_function", "constraint_function", "interval_constraint_function", "jacobian_function"]

Terrain = Literal["ri", "e_max"]


def _check_terrain_kind(terrain: str, model: str) -> None:
    get_model(model)
    if terrain not in ("ri", "e_max"):
        raise InputError(f"terrain {terrain!r} is unknown; choose 'ri' (roughness index) or 'e_max' (metres)")
    if terrain == "e_max" and model not in FORCE_OF_E_MAX:
        raise InputError(
            f"model {model!r} is defined on the roughness index only; use terrain='ri' "
            f"(e_max works with {', '.join(FORCE_OF_E_MAX)})"
        )


def _force(model: str, terrain: Terrain, speed_mps: Any, value: Any, vehicle: Vehicle) -> Any:
    if terrain == "ri":
        force = force_n(speed_mps, vehicle, ri=value, model=model)
    else:
        force = force_n(speed_mps, vehicle, e_max_m=value, model=model)
    # A negative or NaN terrain value is no terrain: NaN, never "admissible". The forces
    # say so too, but an RI of a few 1e-324 below zero becomes e_max = -0.0 (smooth
    # ground) on the way: the input itself is tested here.
    return ca.if_else(value >= 0, force, math.nan)


# ---------------------------------------------------------------------------------------
# Named casadi.Function objects
# ---------------------------------------------------------------------------------------

_TERRAIN_INPUT = {"ri": "ri", "e_max": "e_max_m"}
_TERRAIN_DOC = {"ri": "ri: roughness index RI (dimensionless, >= 0)", "e_max": "e_max_m: worst-case elevation e_max (m, >= 0, Eq. 8)"}


def _vehicle_label(vehicle: Vehicle) -> str:
    """The vehicle's file name without its folder (a Function's doc travels to other
    machines, in pickles and generated code)."""
    return Path(vehicle.name).name if vehicle.name else "(unnamed)"


def _function_name(name: str | None, default: str) -> str:
    out = default if name is None else name
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", out):
        raise InputError(f"function name {out!r} is not a C identifier; use letters, digits and '_'")
    return out


def force_function(
    vehicle: Vehicle,
    *,
    model: str = DEFAULT_MODEL,
    terrain: Terrain = "ri",
    n_stages: int = 1,
    name: str | None = None,
) -> ca.Function:
    """The model's force as a named ``casadi.Function`` with the vehicle folded in.

    Parameters
    ----------
    vehicle : Vehicle
        Its constants become numbers inside the Function.
    model : str, default ``"sbem_tf"`` (:data:`~profileopt.physics.forces.DEFAULT_MODEL`)
        ``"prev_bem"``, ``"iecm"``, ``"sbem_ef"`` or ``"sbem_tf"``.
    terrain : {"ri", "e_max"}, default ``"ri"``
        Second input: the roughness index, or the worst-case elevation in metres (not for
        Prev:BEM).
    n_stages : int, default 1
        Length of the input and output vectors (elementwise over stages).
    name : str, optional
        Function name (a C identifier); default ``"<model>_force_of_<terrain>"``.

    Returns
    -------
    casadi.Function
        Inputs ``speed_mps`` (n_stages x 1, m/s) and ``ri`` (dimensionless) or ``e_max_m``
        (m), output ``force_n`` (n_stages x 1, N). :func:`jacobian_function` gives
        ``jac_force_n_speed_mps`` (N per m/s) and ``jac_force_n_ri`` (N) or
        ``jac_force_n_e_max_m`` (N/m), diagonal. At terrain 0 (smooth ground) the force is 0;
        at a negative or NaN terrain value it is NaN (not terrain, never admissible).
    """
    spec = get_model(model)
    _check_terrain_kind(terrain, model)
    if not (isinstance(n_stages, int) and n_stages >= 1):
        raise InputError(f"n_stages = {n_stages!r}: must be an integer >= 1")
    v = ca.SX.sym("speed_mps", n_stages)
    t = ca.SX.sym(_TERRAIN_INPUT[terrain], n_stages)
    force = _force(model, terrain, v, t, vehicle)
    fname = _function_name(name, f"{model}_force_of_{terrain}")
    doc = (
        f"{spec.label} force (N) of vehicle {_vehicle_label(vehicle)}; inputs speed_mps: "
        f"speed (m/s), {_TERRAIN_DOC[terrain]}; output force_n: force (N); "
        f"limit {spec.limit_n(vehicle):g} N ({spec.limit_key})."
    )
    fn = ca.Function(fname, [v, t], [force], ["speed_mps", _TERRAIN_INPUT[terrain]], ["force_n"])
    fn.__doc__ = doc
    return fn


def constraint_function(
    vehicle: Vehicle,
    *,
    model: str = DEFAULT_MODEL,
    terrain: Terrain = "ri",
    normalised: bool = True,
    n_stages: int = 1,
    name: str | None = None,
) -> ca.Function:
    """The force constraint g(speed, terrain) <= 0 as a named ``casadi.Function``.

    Parameters
    ----------
    vehicle, model, terrain
        As for :func:`force_function`.
    normalised : bool, default True
        g = F / F_limit - 1 (dimensionless) if True, g = F - F_limit (N) if False; both
        are <= 0 exactly when the force is within the limit.
    n_stages : int, default 1
        As for :func:`force_function`.
    name : str, optional
        Function name (a C identifier); default ``"<model>_constraint_of_<terrain>"``.

    Returns
    -------
    casadi.Function
        Inputs ``speed_mps`` (n_stages x 1, m/s) and ``ri`` or ``e_max_m`` (m), output ``g``
        (n_stages x 1) with g <= 0 admissible; g is NaN (never <= 0) at a negative or NaN
        terrain value. :func:`jacobian_function` gives ``jac_g_speed_mps`` and ``jac_g_ri`` /
        ``jac_g_e_max_m``.
    """
    spec = get_model(model)
    force_fn = force_function(vehicle, model=model, terrain=terrain, n_stages=n_stages)
    v = ca.SX.sym("speed_mps", n_stages)
    t = ca.SX.sym(_TERRAIN_INPUT[terrain], n_stages)
    force = force_fn(v, t)
    limit = spec.limit_n(vehicle)
    g = force / limit - 1.0 if normalised else force - limit
    fname = _function_name(name, f"{model}_constraint_of_{terrain}")
    fn = ca.Function(fname, [v, t], [g], ["speed_mps", _TERRAIN_INPUT[terrain]], ["g"])
    unit = "dimensionless, F / F_limit - 1" if normalised else "N, F - F_limit"
    fn.__doc__ = (
        f"{spec.label} force constraint g <= 0 of vehicle {_vehicle_label(vehicle)}; inputs "
        f"speed_mps: speed (m/s), {_TERRAIN_DOC[terrain]}; output g ({unit}); "
        f"F_limit = {limit:g} N."
    )
    return fn


def interval_constraint_function(
    vehicle: Vehicle,
    *,
    model: str = DEFAULT_MODEL,
    n_stages: int = 1,
    name: str | None = None,
) -> ca.Function:
    """The interval rows of :func:`profileopt.mpc.horizon.interval_force_constraints` as a named
    ``casadi.Function``: the force limit at every speed between each interval's entry and
    exit speeds, for every elevation in [e_min, e_max].

    Parameters
    ----------
    vehicle : Vehicle
        Its constants become numbers inside the Function.
    model : str, default ``"sbem_tf"``
        ``"iecm"``, ``"sbem_ef"`` or ``"sbem_tf"`` (Prev:BEM is defined on the RI only).
    n_stages : int, default 1
        Number of intervals (the length of each input vector).
    name : str, optional
        Function name (a C identifier); default ``"<model>_interval_constraint_of_e_max"``.

    Returns
    -------
    casadi.Function
        Inputs ``v_start`` and ``v_end`` (n_stages x 1, m/s), ``e_max_m`` and ``e_min_m``
        (n_stages x 1, m; ``e_min_m`` 0 for every elevation up to e_max); output ``g``
        (rows x 1, interval by interval: 3 rows per interval for SBEM:TF with a force peak,
        else 2), each F / F_limit - 1 <= 0 when admissible, NaN at a negative or NaN
        elevation.
    """
    if not (isinstance(n_stages, int) and not isinstance(n_stages, bool) and n_stages >= 1):
        raise InputError(f"n_stages = {n_stages!r}: must be an integer >= 1")
    _check_terrain_kind("e_max", model)
    v0, v1 = ca.SX.sym("v_start", n_stages), ca.SX.sym("v_end", n_stages)
    e_hi, e_lo = ca.SX.sym("e_max_m", n_stages), ca.SX.sym("e_min_m", n_stages)
    rows = interval_force_constraints(v0, v1, e_hi, vehicle, model=model, e_min_m=e_lo)
    fname = _function_name(name, f"{model}_interval_constraint_of_e_max")
    fn = ca.Function(fname, [v0, v1, e_hi, e_lo], [rows.g], ["v_start", "v_end", "e_max_m", "e_min_m"], ["g"])
    fn.__doc__ = (
        f"{get_model(model).label} force limit over each interval's speeds of vehicle {_vehicle_label(vehicle)}; "
        f"inputs v_start, v_end (m/s), e_max_m, e_min_m (m); output g ({rows.n_force // n_stages} rows per "
        f"interval, F / F_limit - 1 <= 0 admissible); F_limit = {rows.limit_n:g} N."
    )
    return fn


def jacobian_function(fn: ca.Function, name: str | None = None) -> ca.Function:
    """The Jacobian of a one-output Function with the same inputs as ``fn``.

    ``fn.jacobian()`` takes the nominal output as an extra (structurally empty) third
    input, which every call must then pass (``fn.jacobian()(v, ri, 0)``); this Function
    takes exactly the inputs of ``fn`` (``jacobian_function(fn)(v, ri)``), and is what
    :func:`profileopt.mpc.codegen.export_c` generates as the ``_jac`` companions.

    Parameters
    ----------
    fn : casadi.Function
        A Function with one output.
    name : str, optional
        Name of the Jacobian Function; default ``fn.name() + "_jac"``.

    Returns
    -------
    casadi.Function
        ``name`` (default ``fn.name() + "_jac"``): inputs as ``fn``, outputs
        ``jac_<out>_<in>`` for each input, (n_out x n_in) matrices.
    """
    jac = fn.jacobian()
    inputs = [ca.SX.sym(fn.name_in(i), fn.sparsity_in(i)) for i in range(fn.n_in())]
    values = jac.call({fn.name_in(i): inputs[i] for i in range(fn.n_in())})
    names = [jac.name_out(i) for i in range(jac.n_out())]
    return ca.Function(
        name or fn.name() + "_jac",
        inputs,
        [values[n] for n in names],
        [fn.name_in(i) for i in range(fn.n_in())],
        names,
    )
