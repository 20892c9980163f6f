"""The four quarter-car force models, each written once as a CasADi expression.

Every function here builds the force a model predicts when the vehicle drives at speed V
over terrain of a given roughness. Thanks to :func:`profileopt.core.symbolic.elementwise` each
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
import numpy as np

from ..core.symbolic import elementwise, is_symbolic
from ..core.vehicle import require_vehicle
from ..defaults import DEFAULT_MODEL, MODEL_KEYS
from ..errors import InputError
from ..terrain.roughness import check_e_max, check_ri, step_width, worst_case_elevation

if TYPE_CHECKING:
    from ..core.vehicle import Vehicle

__all__ = [
    "DEFAULT_MODEL",
    "DYNAMIC",
    "ForceModel",
    "MODELS",
    "FORCE_OF_E_MAX",
    "get_model",
    "check_e_max_model",
    "force_n",
    "envelope_force_n",
    "transmissibility_peak_ratio",
    "force_peak_ratio",
    "sbem_tf_envelope_force_n",
    "sbem_tf_crawl_bound_n",
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
    # A negative or NaN terrain value has no force at all: NaN, never "admissible".
    return ca.if_else(e_max_m > 0, force, ca.if_else(e_max_m == 0, 0, math.nan))


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


def transmissibility_peak_ratio(damping_ratio: float) -> float:
    """The frequency ratio r_p = sqrt(sqrt(1 + 8 zeta^2) - 1) / (2 zeta) where the force
    transmissibility T(r) of Eq. (13) is largest (dimensionless).

    With x = r^2 and a = 4 zeta^2, T^2 = (1 + a x) / ((1 - x)^2 + a x); setting its
    derivative in x to zero gives a x^2 + 2 x - 2 = 0, whose positive root is
    x = (sqrt(1 + 8 zeta^2) - 1) / (4 zeta^2). T rises on [0, r_p] and falls beyond it.

    Parameters
    ----------
    damping_ratio : float
        Suspension damping ratio zeta (dimensionless), > 0.
    """
    zeta = float(damping_ratio)
    return math.sqrt(math.sqrt(1.0 + 8.0 * zeta * zeta) - 1.0) / (2.0 * zeta)


def force_peak_ratio(damping_ratio: float) -> float | None:
    """The frequency ratio r_phi where the SBEM:TF force at a fixed elevation has its
    interior local maximum, or None if the force grows with speed everywhere (dimensionless).

    At a fixed elevation e the force of Eq. (13) is F = k e phi(r) with phi(r) = r^2 T(r),
    T the force transmissibility and r = pi V / (2 X_w(e) wn) proportional to the speed.
    With x = r^2 and a = 4 zeta^2, phi^2 = x^2 (1 + a x) / ((1 - x)^2 + a x); its
    derivative in x has the sign of the cubic a x^3 + 2 a (a - 2) x^2 + (4 a - 2) x + 2,
    which is 2 at x = 0. For zeta < 1 / (2 sqrt 2) (a < 1/2) it has two positive roots:
    phi rises to r_phi = sqrt(smaller root) (just above resonance, above the peak of T),
    falls to the larger one and rises again (phi ~ 2 zeta r at high r). For
    zeta >= 1 / (2 sqrt 2) the cubic has no positive root (a double one at x = 2 on the
    boundary) and phi grows everywhere.

    Parameters
    ----------
    damping_ratio : float
        Suspension damping ratio zeta (dimensionless), > 0.

    Returns
    -------
    float or None
        r_phi, or None when phi has no interior maximum.

    Raises
    ------
    InputError
        A damping ratio that is not a number > 0.
    """
    zeta = float(damping_ratio)
    if not (math.isfinite(zeta) and zeta > 0):
        raise InputError(f"damping_ratio = {damping_ratio!r}: must be a number > 0")
    a = 4.0 * zeta * zeta
    coefficients = [a, 2.0 * a * (a - 2.0), 4.0 * a - 2.0, 2.0]
    if a >= 0.5:
        return None
    roots = np.roots(coefficients)
    real = np.sort(roots.real[(np.abs(roots.imag) <= 1e-9 * np.abs(roots)) & (roots.real > 0)])
    if real.size == 0:  # pragma: no cover - a < 1/2 always has two positive roots
        return None
    x = float(real[0])
    cubic = np.polynomial.Polynomial(coefficients[::-1])
    slope = cubic.deriv()
    for _ in range(3):  # polish to full precision
        d = float(slope(x))
        if d == 0.0:
            break
        x -= float(cubic(x)) / d
    return math.sqrt(x)


@elementwise
def sbem_tf_envelope_force_n(speed_mps: Any, e_min_m: Any, e_max_m: Any, vehicle: "Vehicle") -> Any:
    """The largest SBEM:TF force (Eq. 13) over every elevation e in [e_min, e_max], in N:
    an upper bound, exact when e_min = e_max and at every speed where the force grows with e.

    SBEM:TF is not monotone in e at a fixed speed: a smaller step is also narrower
    (X_w of Eq. 2), so it is climbed faster, and near resonance that can raise the force.
    Write F = k e r^2 T(r) with r = pi V / (2 X_w(e) wn) and T the transmissibility of
    Eq. (13). The factor e r^2 = (pi V / (2 wn))^2 e / X_w(e)^2 grows with e (it is
    (pi V / (2 wn))^2 / (2 r_w - e) below the wheel radius r_w, linear in e above it), so it
    is at most its value at e_max. r falls as e grows, so over the range it lies in
    [r(e_max), r(e_min)], where T is at most T(clip(r_p, r(e_max), r(e_min))) (T rises up
    to its peak r_p, :func:`transmissibility_peak_ratio`, and falls beyond). The product
    of the two maxima bounds the force. Where r(e_max) >= r_p (every speed above
    2 wn r_w r_p / pi, where even the widest step X_w = r_w is crossed above resonance) the
    clip picks r(e_max) and the bound is F(V, e_max) exactly; below that speed it is
    conservative by at most the factor (2 r_w - e) / (2 r_w - e_max) of the worst e.

    Parameters
    ----------
    speed_mps : number, array, DM, SX or MX
        Forward speed V (m/s).
    e_min_m, e_max_m : number, array, DM, SX or MX
        The range of elevation amplitudes e (m), 0 <= e_min <= e_max; usually the e_max
        (Eq. 8) of the least and of the roughest roughness window a stretch of route holds.
    vehicle : Vehicle
        Quarter-car constants and the wheel radius.

    Returns
    -------
    Same kind as the inputs: force (N). NaN for a negative or NaN elevation.
    """
    k, zeta, wn = vehicle.spring_n_per_m, vehicle.damping_ratio, vehicle.natural_frequency_radps
    x_hi = step_width(e_max_m, vehicle)
    # e_min = 0 is a step of no width, r = infinity: a tiny floor keeps r finite (then T(r)
    # is far past its peak and the clip picks r_p anyway) and the derivatives free of NaN.
    x_lo = ca.fmax(step_width(e_min_m, vehicle), 1e-12 * x_hi)
    r_hi = base_frequency_radps(speed_mps, e_max_m, vehicle) / wn  # r at e_max, the least
    r_lo = math.pi * speed_mps / (2.0 * x_lo * wn)  # r at e_min, the largest
    r = ca.fmax(r_hi, ca.fmin(transmissibility_peak_ratio(zeta), r_lo))
    damping = (2.0 * zeta * r) ** 2
    ratio = (1.0 + damping) / ((1.0 - r**2) ** 2 + damping)
    force = _smooth_ground_is_zero(e_max_m, k * e_max_m * r_hi**2 * ca.sqrt(ratio))
    return ca.if_else(e_min_m >= 0, force, math.nan)


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
    force = k * amplitude * ca.sqrt(1.0 + (2.0 * zeta * w / wn) ** 2)
    return ca.if_else(ri >= 0, force, math.nan)  # a negative or NaN RI: NaN, never "admissible"


def _of_e_max(force_of_e: Callable) -> Callable:
    def builder(speed_mps: Any, ri: Any, vehicle: "Vehicle") -> Any:
        # the RI itself is tested: a tiny negative RI rounds to e_max = -0.0, not below 0
        return ca.if_else(ri >= 0, force_of_e(speed_mps, worst_case_elevation(ri, vehicle), vehicle), math.nan)

    builder.__name__ = force_of_e.__name__ + "_of_ri"
    return builder


@elementwise
def sbem_tf_crawl_bound_n(e_max_m: Any, vehicle: "Vehicle") -> Any:
    """An upper bound (N) on the SBEM:TF force at every speed up to 2 wn r_w r_p / pi and
    every elevation in [0, e_max]: k (r_p r_w)^2 e_max / X_w(e_max)^2 T(r_p).

    Below that speed (the only speeds where the force can fall as e grows, see
    :func:`sbem_tf_envelope_force_n`) F = k P T(r) with P = (pi V / (2 wn))^2 e / X_w(e)^2
    growing in V and e, so P is at most its value at that speed and e_max, where
    pi V / (2 wn) = r_p r_w; and T is at most T(r_p). Where this is within the limit, the
    bands over an elevation range equal those at its top (the forces agree above that speed,
    both are admissible below it).

    Parameters
    ----------
    e_max_m : number, array, DM, SX or MX
        The top of the elevation range (m), >= 0.
    vehicle : Vehicle
    """
    k, zeta, r_w = vehicle.spring_n_per_m, vehicle.damping_ratio, vehicle.wheel_radius_m
    r_p = transmissibility_peak_ratio(zeta)
    a = 4.0 * zeta**2 * r_p**2
    peak = math.sqrt((1.0 + a) / ((1.0 - r_p**2) ** 2 + a))
    x_w = step_width(e_max_m, vehicle)
    return _smooth_ground_is_zero(e_max_m, k * (r_p * r_w) ** 2 * e_max_m / x_w**2 * peak)


def _monotone_envelope(force_of_ri: Callable) -> Callable:
    """The largest force over RI in [ri_min, ri_max] of a model whose force grows with the
    RI at every speed: its force at ri_max (NaN when ri_min is negative or NaN)."""
    def builder(speed_mps: Any, ri_min: Any, ri_max: Any, vehicle: "Vehicle") -> Any:
        return ca.if_else(ri_min >= 0, force_of_ri(speed_mps, ri_max, vehicle), math.nan)

    builder.__name__ = force_of_ri.__name__ + "_envelope"
    return builder


def _sbem_tf_envelope_of_ri(speed_mps: Any, ri_min: Any, ri_max: Any, vehicle: "Vehicle") -> Any:
    force = sbem_tf_envelope_force_n.symbolic(speed_mps, worst_case_elevation(ri_min, vehicle),
                                              worst_case_elevation(ri_max, vehicle), vehicle)
    return ca.if_else((ri_min >= 0) * (ri_max >= 0), force, math.nan)  # as _of_e_max: test the RI itself


_sbem_tf_envelope_of_ri.__name__ = "sbem_tf_envelope_of_ri"  # a CasADi Function name


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
    envelope_of_ri : callable
        ``envelope_of_ri(speed_mps, ri_min, ri_max, vehicle)``: the largest force (N) over
        every RI in [ri_min, ri_max] (an upper bound for SBEM:TF, see
        :func:`sbem_tf_envelope_force_n`; the force at ri_max for the models whose force
        grows with the RI), for any kind of argument.
    monotone : bool
        Whether the force grows with the RI at every speed (IECM: e / X_w grows with e;
        SBEM:EF: e w_b does; Prev:BEM is linear in the RI). SBEM:TF does not.
    """

    key: str
    label: str
    limit_key: str
    quantity: str
    of_ri: Callable
    envelope_of_ri: Callable
    monotone: bool

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

    def envelope_force_n(self, speed_mps: Any, ri_min: Any, ri_max: Any, vehicle: "Vehicle") -> Any:
        """The largest force (N) at speed (m/s) over every RI in [ri_min, ri_max].

        Parameters
        ----------
        speed_mps : number, array, DM, SX or MX
            Forward speed V (m/s); broadcast against the RI range.
        ri_min, ri_max : number, array, DM, SX or MX
            The range of roughness indices (dimensionless), 0 <= ri_min <= ri_max.
        vehicle : Vehicle
        """
        check_ri(ri_min)
        check_ri(ri_max)
        _check_ordered(ri_min, ri_max, "ri_min", "ri_max")
        return self.envelope_of_ri(speed_mps, ri_min, ri_max, vehicle)


def _check_ordered(low: Any, high: Any, low_name: str, high_name: str) -> None:
    """Raise InputError if a numeric ``low`` exceeds ``high`` anywhere (symbols pass)."""
    if is_symbolic(low, high):
        return
    lo = np.asarray(low.full() if isinstance(low, ca.DM) else low, dtype=float)
    hi = np.asarray(high.full() if isinstance(high, ca.DM) else high, dtype=float)
    if np.any(lo > hi):
        raise InputError(f"{low_name} must not exceed {high_name} (a range is given as its least and largest value)")


def _model(key: str, label: str, limit_key: str, quantity: str, of_ri: Callable) -> ForceModel:
    monotone = key != "sbem_tf"
    envelope = _monotone_envelope(of_ri.symbolic) if monotone else _sbem_tf_envelope_of_ri
    return ForceModel(key, label, limit_key, quantity, of_ri, elementwise(envelope), monotone)


MODELS: dict[str, ForceModel] = {
    "prev_bem": _model("prev_bem", "Prev:BEM", "max_excitation_force_n", "excitation", prev_bem_force_n),
    "iecm": _model("iecm", "IECM", "max_excitation_force_n", "excitation", elementwise(_of_e_max(iecm_force_n))),
    "sbem_ef": _model("sbem_ef", "SBEM:EF", "max_excitation_force_n", "excitation",
                      elementwise(_of_e_max(sbem_ef_force_n))),
    "sbem_tf": _model("sbem_tf", "SBEM:TF", "max_transmitted_force_n", "transmitted",
                      elementwise(_of_e_max(sbem_tf_force_n))),
}
if tuple(MODELS) != MODEL_KEYS:  # pragma: no cover - the command line lists MODEL_KEYS
    raise RuntimeError("profileopt.defaults.MODEL_KEYS must name the models of MODELS, in order")


def _no_formula(*args: Any) -> Any:
    raise InputError("the dynamic model has no force formula of the RI or e_max: its force is the quarter car's "
                     "response simulated on the route's own samples (profileopt.physics.simulate); choose one "
                     "of the paper's models (sbem_tf, sbem_ef, iecm, prev_bem) here")


#: The ``dynamic`` model: the transmitted force of the quarter car driven over the route's own
#: samples, as :func:`~profileopt.physics.simulate.simulate_quarter_car` computes it, held to
#: ``max_transmitted_force_n``. It has no formula of the RI (its ``of_ri`` and
#: ``envelope_of_ri`` refuse, naming the paper's models); the planner imposes it by
#: simulating (:mod:`profileopt.planning.dynamic`). Not one of :data:`MODELS` (the paper's).
DYNAMIC = ForceModel("dynamic", "dynamic", "max_transmitted_force_n", "transmitted", _no_formula, _no_formula, False)


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
        ``"prev_bem"``, ``"iecm"``, ``"sbem_ef"``, ``"sbem_tf"`` or ``"dynamic"``
        (:data:`DYNAMIC`).

    Raises
    ------
    InputError
        Another ``model``; the message names the choices.
    """
    if model == DYNAMIC.key:
        return DYNAMIC
    try:
        return MODELS[model]
    except (KeyError, TypeError):
        raise InputError(f"model {model!r} is unknown; choose one of {', '.join(MODELS)} or dynamic") from None


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
    """
    vehicle = require_vehicle(vehicle, "force_n")
    spec = get_model(model)
    if (ri is None) == (e_max_m is None):
        raise InputError("give exactly one of ri (roughness index) and e_max_m (worst-case elevation, m)")
    if e_max_m is None:
        return spec.force_n(speed_mps, ri, vehicle)
    check_e_max_model(model)
    check_e_max(e_max_m)
    return FORCE_OF_E_MAX[model](speed_mps, e_max_m, vehicle)


def envelope_force_n(speed_mps: Any, vehicle: "Vehicle", *, ri_range: tuple[Any, Any] | None = None,
                     e_range_m: tuple[Any, Any] | None = None, model: str = DEFAULT_MODEL) -> Any:
    """The largest force (N) that ``model`` predicts at ``speed_mps`` over a range of terrain.

    A stretch of route seen through sliding roughness windows holds a range of RI values,
    not one: its admissible speeds are those admissible for every value of the range. This
    is the force those speeds are held to. For IECM, SBEM:EF and Prev:BEM, whose force
    grows with the terrain value, it is the force at the top of the range; for SBEM:TF it
    is the bound of :func:`sbem_tf_envelope_force_n`, exact at every speed where the force
    grows with e. With both ends equal it is :func:`force_n`.

    Parameters
    ----------
    speed_mps : number, array, DM, SX or MX
        Forward speed (m/s); broadcast against the range.
    vehicle : Vehicle
    ri_range : (ri_min, ri_max), optional
        Least and largest roughness index (dimensionless), 0 <= ri_min <= ri_max; numbers,
        arrays, DM, SX or MX.
    e_range_m : (e_min_m, e_max_m), optional
        Least and largest worst-case elevation (m) of Eq. (8), for IECM, SBEM:EF, SBEM:TF.
    model : str, default ``"sbem_tf"`` (:data:`DEFAULT_MODEL`)

    Returns
    -------
    Same kind as the inputs: force (N).

    Raises
    ------
    InputError
        Unknown ``model``, both or neither range, ``e_range_m`` with Prev:BEM, a NaN or
        negative value, or a range whose least value exceeds its largest.
    """
    spec = get_model(model)
    if (ri_range is None) == (e_range_m is None):
        raise InputError("give exactly one of ri_range (roughness index) and e_range_m (worst-case elevation, m)")
    if ri_range is not None:
        ri_min, ri_max = ri_range
        return spec.envelope_force_n(speed_mps, ri_min, ri_max, vehicle)
    check_e_max_model(model)
    e_min, e_max = e_range_m
    check_e_max(e_min)
    check_e_max(e_max)
    _check_ordered(e_min, e_max, "e_min_m", "e_max_m")
    if model == "sbem_tf":
        return sbem_tf_envelope_force_n(speed_mps, e_min, e_max, vehicle)
    return FORCE_OF_E_MAX[model](speed_mps, e_max, vehicle)
