"""The four quarter-car force models, each written once as a CasADi expression.

Every function here builds the force a model predicts when the vehicle drives at speed V
over terrain of a given roughness. Thanks to :func:`profileopt.symbolic.elementwise` each
one takes plain numbers, numpy arrays, ``casadi.DM``, ``SX`` or ``MX`` and returns the same
kind, so the planner, the constraint exports, the C code and the numeric evaluation all use
these very expressions. The models know nothing of any optimisation problem.

Equation numbers are those of Wilson et al. (summarised with the project's errata in ``docs/paper-notes.md``), which holds the
errata applied here. Quarter-car constants: k = m wn^2, c = 2 zeta m wn.

Models
------
``prev_bem``
    Prev:BEM, the base-excitation model of the paper's reference [11], as *reconstructed*
    in docs/paper-notes.md (the text of [11] is not available): a sinusoid of amplitude
    Y = sqrt(2) RI h at the estimated maximum terrain frequency f, F = k Y sqrt(1 + (2 zeta
    w / wn)^2) with w = 2 pi f V. Limited by ``max_excitation_force_n``.
``iecm``
    Instantaneous Elevation Change Model (Eq. 6): F = k e (1 + 2 zeta V / (wn X_w)).
    Limited by ``max_excitation_force_n``.
``sbem_ef``
    Sinusoidal Base Excitation Model, excitation force (Eq. 9-11, simplified exactly as in
    docs/paper-notes.md): F = e sqrt(k^2 + (c w_b)^2), w_b = pi V / (2 X_w) (Eq. 12). Limited by
    ``max_excitation_force_n``.
``sbem_tf``
    Sinusoidal Base Excitation Model, transmitted force (Eq. 12-13): F_T = k e r^2 sqrt((1 +
    (2 zeta r)^2) / ((1 - r^2)^2 + (2 zeta r)^2)), r = w_b / wn. Not monotone in V for a
    lightly damped suspension (resonance). Limited by ``max_transmitted_force_n``.

For the three paper models e is the worst-case elevation e_max of Eq. (8); at e = 0
(perfectly smooth ground, RI = 0) the force is 0 (docs/paper-notes.md: no force limit).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any, Callable

import casadi as ca

from .symbolic import elementwise
from ._deprecation import OldCall, old_forms
from .defaults import DEFAULT_MODEL, MODEL_KEYS
from .errors import InputError
from .terrain import check_e_max, check_ri, step_width, worst_case_elevation

if TYPE_CHECKING:
    from .vehicle import Vehicle

__all__ = [
    "DEFAULT_MODEL",
    "ForceModel",
    "MODELS",
    "FORCE_OF_E_MAX",
    "get_model",
    "check_e_max_model",
    "force_n",
    "iecm_force_n",
    "sbem_ef_force_n",
    "sbem_tf_force_n",
    "prev_bem_force_n",
    "base_frequency_radps",
]


@elementwise
def base_frequency_radps(speed_mps: Any, e_max_m: Any, vehicle: "Vehicle") -> Any:
    """SBEM base-excitation frequency w_b = pi V / (2 X_w) (Eq. 12), in rad/s.

    The step of width X_w is climbed in a quarter period of the sinusoid (Fig. 4).

    Parameters
    ----------
    speed_mps : number, array, DM, SX or MX
        Forward speed V (m/s).
    e_max_m : number, array, DM, SX or MX
        Step height e (m), usually e_max of Eq. (8).
    vehicle : Vehicle
        Supplies the wheel radius.
    """
    return math.pi * speed_mps / (2.0 * step_width(e_max_m, vehicle))


def _smooth_ground_is_zero(e_max_m: Any, force: Any) -> Any:
    # RI = 0 makes every formula 0/0; the limit is no force at all (docs/paper-notes.md).
    return ca.if_else(e_max_m > 0, force, 0)


@elementwise
def iecm_force_n(speed_mps: Any, e_max_m: Any, vehicle: "Vehicle") -> Any:
    """IECM excitation force F = k e (2 zeta V / (wn X_w) + 1) (Eq. 6, F_hat = F / k), in N.

    Parameters
    ----------
    speed_mps : number, array, DM, SX or MX
        Forward speed V (m/s).
    e_max_m : number, array, DM, SX or MX
        Step height e (m), usually e_max of Eq. (8).
    vehicle : Vehicle
        Quarter-car constants.
    """
    k, zeta, wn = vehicle.spring_n_per_m, vehicle.damping_ratio, vehicle.natural_frequency_radps
    x_w = step_width(e_max_m, vehicle)
    return _smooth_ground_is_zero(e_max_m, k * e_max_m * (2.0 * zeta * speed_mps / (wn * x_w) + 1.0))


@elementwise
def sbem_ef_force_n(speed_mps: Any, e_max_m: Any, vehicle: "Vehicle") -> Any:
    """SBEM:EF peak excitation force F_max = e sqrt(k^2 + (c w_b)^2) (Eq. 11), in N.

    Eq. (11) with t_max of Eq. (10) substituted reduces exactly to this form (docs/paper-notes.md),
    which is defined at V = 0 as well (F = k e, the static force).

    Parameters
    ----------
    speed_mps : number, array, DM, SX or MX
        Forward speed V (m/s).
    e_max_m : number, array, DM, SX or MX
        Elevation amplitude e (m), usually e_max of Eq. (8).
    vehicle : Vehicle
        Quarter-car constants.
    """
    k, c = vehicle.spring_n_per_m, vehicle.damping_ns_per_m
    w_b = base_frequency_radps(speed_mps, e_max_m, vehicle)
    return _smooth_ground_is_zero(e_max_m, e_max_m * ca.sqrt(k**2 + (c * w_b) ** 2))


@elementwise
def sbem_tf_force_n(speed_mps: Any, e_max_m: Any, vehicle: "Vehicle") -> Any:
    """SBEM:TF peak force transmitted to the frame (Eq. 13), in N.

    F_T = k e r^2 sqrt((1 + (2 zeta r)^2) / ((1 - r^2)^2 + (2 zeta r)^2)), r = w_b / wn,
    the textbook base-excitation force transmissibility (Inman, Engineering Vibration,
    section 2.4), checked against a time-domain simulation (docs/paper-notes.md).

    Parameters
    ----------
    speed_mps : number, array, DM, SX or MX
        Forward speed V (m/s).
    e_max_m : number, array, DM, SX or MX
        Elevation amplitude e (m), usually e_max of Eq. (8).
    vehicle : Vehicle
        Quarter-car constants.
    """
    k, zeta, wn = vehicle.spring_n_per_m, vehicle.damping_ratio, vehicle.natural_frequency_radps
    r = base_frequency_radps(speed_mps, e_max_m, vehicle) / wn
    damping = (2.0 * zeta * r) ** 2
    ratio = (1.0 + damping) / ((1.0 - r**2) ** 2 + damping)
    return _smooth_ground_is_zero(e_max_m, k * e_max_m * r**2 * ca.sqrt(ratio))


@elementwise
def prev_bem_force_n(speed_mps: Any, ri: Any, vehicle: "Vehicle") -> Any:
    """Prev:BEM excitation force, the project's reconstruction of reference [11], in N.

    F = k Y sqrt(1 + (2 zeta w / wn)^2) with Y = sqrt(2) RI h (the amplitude of a sinusoid
    whose RI is RI) and w = 2 pi f V at the estimated maximum terrain frequency f
    (``terrain_frequency_cpm``). A reconstruction, labelled as such: see docs/paper-notes.md.

    Parameters
    ----------
    speed_mps : number, array, DM, SX or MX
        Forward speed V (m/s).
    ri : number, array, DM, SX or MX
        Roughness index (dimensionless).
    vehicle : Vehicle
        Quarter-car constants and f (cycles/m).
    """
    k, zeta, wn = vehicle.spring_n_per_m, vehicle.damping_ratio, vehicle.natural_frequency_radps
    amplitude = math.sqrt(2.0) * ri * vehicle.ground_clearance_m
    w = 2.0 * math.pi * vehicle.terrain_frequency_cpm * speed_mps
    return k * amplitude * ca.sqrt(1.0 + (2.0 * zeta * w / wn) ** 2)


def _of_e_max(force_of_e: Callable) -> Callable:
    def builder(speed_mps: Any, ri: Any, vehicle: "Vehicle") -> Any:
        return force_of_e(speed_mps, worst_case_elevation(ri, vehicle), vehicle)

    builder.__name__ = force_of_e.__name__ + "_of_ri"
    return builder


@dataclasses.dataclass(frozen=True)
class ForceModel:
    """One of the four force models and the vehicle limit it is held to.

    Attributes
    ----------
    key : str
        ``"prev_bem"``, ``"iecm"``, ``"sbem_ef"`` or ``"sbem_tf"``.
    label : str
        The paper's name, e.g. ``"SBEM:TF"``.
    limit_key : str
        The vehicle attribute holding its force limit (N).
    quantity : str
        ``"excitation"`` or ``"transmitted"``.
    of_ri : callable
        ``of_ri(speed_mps, ri, vehicle)``: the force (N) against speed (m/s) and RI, for
        any kind of argument (numbers, arrays, DM, SX, MX).
    """

    key: str
    label: str
    limit_key: str
    quantity: str
    of_ri: Callable

    def limit_n(self, vehicle: "Vehicle") -> float:
        """The force limit this model is held to (N).

        Parameters
        ----------
        vehicle : Vehicle
            Holds the limit in its attribute ``limit_key``.
        """
        return float(getattr(vehicle, self.limit_key))

    def force_n(self, speed_mps: Any, ri: Any, vehicle: "Vehicle") -> Any:
        """The predicted force (N) at speed (m/s) over terrain of roughness ``ri``.

        Parameters
        ----------
        speed_mps : number, array, DM, SX or MX
            Forward speed V (m/s); broadcast against ``ri``.
        ri : number, array, DM, SX or MX
            Roughness index (dimensionless), >= 0.
        vehicle : Vehicle
        """
        check_ri(ri)
        return self.of_ri(speed_mps, ri, vehicle)


MODELS: dict[str, ForceModel] = {
    "prev_bem": ForceModel("prev_bem", "Prev:BEM", "max_excitation_force_n", "excitation", prev_bem_force_n),
    "iecm": ForceModel("iecm", "IECM", "max_excitation_force_n", "excitation", elementwise(_of_e_max(iecm_force_n))),
    "sbem_ef": ForceModel("sbem_ef", "SBEM:EF", "max_excitation_force_n", "excitation", elementwise(_of_e_max(sbem_ef_force_n))),
    "sbem_tf": ForceModel("sbem_tf", "SBEM:TF", "max_transmitted_force_n", "transmitted", elementwise(_of_e_max(sbem_tf_force_n))),
}
if tuple(MODELS) != MODEL_KEYS:  # pragma: no cover - the command line lists MODEL_KEYS
    raise RuntimeError("profileopt.defaults.MODEL_KEYS must name the models of MODELS, in order")


#: The models defined on the worst-case elevation e_max (m) of Eq. (8), each with its own
#: expression ``force(speed_mps, e_max_m, vehicle)`` (N). Prev:BEM is defined on the RI only.
FORCE_OF_E_MAX: dict[str, Callable[..., Any]] = {
    "iecm": iecm_force_n,
    "sbem_ef": sbem_ef_force_n,
    "sbem_tf": sbem_tf_force_n,
}


def get_model(model: str) -> ForceModel:
    """The :class:`ForceModel` called ``model``.

    Parameters
    ----------
    model : str
        ``"prev_bem"``, ``"iecm"``, ``"sbem_ef"`` or ``"sbem_tf"``.

    Raises
    ------
    InputError
        Another ``model``; the message names the choices.
    """
    try:
        return MODELS[model]
    except (KeyError, TypeError):
        raise InputError(f"model {model!r} is unknown; choose one of {', '.join(MODELS)}") from None


def check_e_max_model(model: str) -> None:
    """Raise :class:`~profileopt.errors.InputError` unless ``model`` is defined on e_max.

    Parameters
    ----------
    model : str
        A model key; Prev:BEM (defined on the roughness index only) and unknown keys fail.
    """
    get_model(model)
    if model not in FORCE_OF_E_MAX:
        raise InputError(
            f"model {model!r} is defined on the roughness index only; give ri instead of e_max_m "
            f"(e_max_m works with {', '.join(FORCE_OF_E_MAX)})"
        )


def _force_n_old_forms(call: OldCall) -> None:
    call.model_first(("speed_mps", "ri", "vehicle"), "force_n(model, speed_mps, ri, vehicle) is deprecated, use "
                     "force_n(speed_mps, vehicle, ri=ri, model=model)")


@old_forms(_force_n_old_forms)
def force_n(speed_mps: Any, vehicle: "Vehicle", *, ri: Any = None, e_max_m: Any = None,
            model: str = DEFAULT_MODEL) -> Any:
    """The force (N) that ``model`` predicts at ``speed_mps`` over the given terrain.

    Give the terrain as exactly one of ``ri`` (every model) and ``e_max_m`` (IECM, SBEM:EF,
    SBEM:TF). Both give the very same expression: ``ri`` is turned into e_max by Eq. (8).

    Parameters
    ----------
    speed_mps : number, array, DM, SX or MX
        Forward speed (m/s); broadcast against the terrain value.
    vehicle : Vehicle
    ri : number, array, DM, SX or MX, optional
        Roughness index (dimensionless), >= 0.
    e_max_m : number, array, DM, SX or MX, optional
        Worst-case elevation e_max (m) of Eq. (8), >= 0.
    model : str, default ``"sbem_tf"`` (:data:`DEFAULT_MODEL`)
        ``"prev_bem"``, ``"iecm"``, ``"sbem_ef"`` or ``"sbem_tf"``.

    Returns
    -------
    Same kind as the inputs (a float for numbers): force (N).

    Raises
    ------
    InputError
        Unknown ``model``, both or neither of ``ri`` and ``e_max_m``, ``e_max_m`` with
        Prev:BEM, or a NaN or negative terrain value.

    Notes
    -----
    The old call ``force_n(model, speed_mps, ri, vehicle)`` still works for one release,
    with a ``DeprecationWarning``.
    """
    spec = get_model(model)
    if (ri is None) == (e_max_m is None):
        raise InputError("give exactly one of ri (roughness index) and e_max_m (worst-case elevation, m)")
    if e_max_m is None:
        return spec.force_n(speed_mps, ri, vehicle)
    check_e_max_model(model)
    check_e_max(e_max_m)
    return FORCE_OF_E_MAX[model](speed_mps, e_max_m, vehicle)
