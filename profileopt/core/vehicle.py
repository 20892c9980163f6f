"""Vehicle model files: a frozen, validated quarter-car description loaded from TOML.

A vehicle file (``models/*.toml``) holds the keys of :class:`Vehicle`, in SI units: the
quarter car and planning limits always, the limits of turns and hills (lateral acceleration,
rollover, friction, drive power) when the file gives them.
Bundled files are found by name (``load_vehicle("atv")``) both in a source checkout and in
an installed wheel, where they ship as the package ``profileopt.models``.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from importlib import resources
from pathlib import Path

from ..errors import InputError

__all__ = ["Vehicle", "load_vehicle", "bundled_vehicles", "vehicle_reference", "names_vehicle_file", "PLAUSIBLE_RANGES",
           "OPTIONAL_KEYS", "require_vehicle"]

# key -> (unit, what it is). Order is the order of the dataclass fields and of the files.
_UNITS: dict[str, tuple[str, str]] = {
    "quarter_mass_kg": ("kg", "sprung mass carried by one wheel"),
    "ground_clearance_m": ("m", "ground clearance h"),
    "wheel_radius_m": ("m", "wheel radius r"),
    "natural_frequency_radps": ("rad/s", "suspension natural frequency wn"),
    "damping_ratio": ("-", "suspension damping ratio zeta"),
    "confidence": ("-", "probability Pe that e <= e_max, in (0.5, 1)"),
    "max_excitation_force_n": ("N", "allowable excitation force"),
    "max_transmitted_force_n": ("N", "allowable transmitted force"),
    "max_speed_mps": ("m/s", "top speed"),
    "terrain_frequency_cpm": ("cycles/m", "Prev:BEM's estimated maximum terrain frequency"),
    "max_accel_mps2": ("m/s^2", "largest acceleration"),
    "max_decel_mps2": ("m/s^2", "largest deceleration, a positive number"),
    "max_jerk_mps3": ("m/s^3", "largest jerk"),
}

# Optional keys (issue 11: turns and hills): a file without them plans exactly as before, with
# the limits they set off. key -> (unit, what it is), in file order.
_OPTIONAL_UNITS: dict[str, tuple[str, str]] = {
    "max_lateral_accel_mps2": ("m/s^2", "largest lateral acceleration in turns"),
    "track_width_m": ("m", "track width t (between the wheels' centres)"),
    "cg_height_m": ("m", "height h_cg of the centre of gravity above the ground"),
    "friction_coefficient": ("-", "tyre-ground friction coefficient mu"),
    "mass_kg": ("kg", "mass of the whole vehicle"),
    "max_power_w": ("W", "largest drive power at the wheels"),
    "min_turn_radius_m": ("m", "smallest radius the vehicle can turn in (its turning circle's, at its centre)"),
}

#: The optional keys of turns and hills, in file order: a vehicle without any of them plans
#: as before they existed (:func:`profileopt.physics.motion.plans_on_grades`). Not
#: ``min_turn_radius_m``: the turning circle is kept with the lateral limit, and does nothing
#: without it.
OPTIONAL_KEYS: tuple[str, ...] = tuple(key for key in _OPTIONAL_UNITS if key != "min_turn_radius_m")

#: Optional keys that only make sense together: rollover needs both track width and centre of
#: gravity height, the power limit needs the whole vehicle's mass.
_PAIRED_KEYS = (("track_width_m", "cg_height_m"), ("mass_kg", "max_power_w"))

#: The keys that set a lateral acceleration limit (either one, or both of the pair): the
#: turning circle is kept by that limit's module (:mod:`profileopt.planning.limits.lateral`),
#: so a vehicle file's ``min_turn_radius_m`` needs one of them (a Vehicle made in code
#: without them has its turn limits off, the turning circle with them).
_LATERAL_KEYS = ("max_lateral_accel_mps2", "track_width_m")

#: key -> (smallest, largest) value a ground vehicle can physically have, in the key's unit.
#: Wide on purpose (a 1 kg robot corner to a 400 t mining truck's, walking pace to beyond any
#: off-road vehicle); a value outside is a unit mistake or a typo, and would make the force
#: models overflow or divide by almost nothing (issue 13). The lower force limit stays below
#: the 1 N the tests use for "a very weak frame".
PLAUSIBLE_RANGES: dict[str, tuple[float, float]] = {
    "quarter_mass_kg": (0.1, 1e5),
    "ground_clearance_m": (1e-3, 5.0),
    "wheel_radius_m": (1e-3, 5.0),
    "natural_frequency_radps": (0.1, 1e3),
    "damping_ratio": (1e-3, 10.0),
    "confidence": (0.5, 1.0),  # open interval, checked separately
    "max_excitation_force_n": (1e-3, 1e8),
    "max_transmitted_force_n": (1e-3, 1e8),
    "max_speed_mps": (0.01, 200.0),
    "terrain_frequency_cpm": (1e-3, 100.0),
    "max_accel_mps2": (1e-3, 100.0),
    "max_decel_mps2": (1e-3, 100.0),
    "max_jerk_mps3": (1e-3, 1e4),
    "max_lateral_accel_mps2": (1e-2, 100.0),
    "track_width_m": (0.05, 20.0),
    "cg_height_m": (0.01, 20.0),
    "friction_coefficient": (0.01, 3.0),
    "mass_kg": (0.4, 1e6),
    "max_power_w": (1.0, 1e8),
    "min_turn_radius_m": (0.01, 50.0),
}


@dataclasses.dataclass(frozen=True)
class Vehicle:
    """One quarter-car corner of a vehicle and its planning limits (SI units).

    Attributes are the keys of a vehicle file. Every value must be a finite number within
    :data:`PLAUSIBLE_RANGES` (a ground vehicle's); ``confidence`` must lie in (0.5, 1). Construction validates and raises
    :class:`~profileopt.errors.InputError` (a ``ValueError``) otherwise.

    Attributes
    ----------
    quarter_mass_kg : float
        Sprung mass m carried by one wheel (kg).
    ground_clearance_m : float
        Ground clearance h (m); the RI is elevation divided by h (Eq. 1).
    wheel_radius_m : float
        Wheel radius r (m); the step width X_w saturates at r (Eq. 2).
    natural_frequency_radps : float
        Suspension natural frequency wn (rad/s).
    damping_ratio : float
        Suspension damping ratio zeta (dimensionless).
    confidence : float
        Pe, the probability that an elevation stays below e_max (Eq. 8), in (0.5, 1).
    max_excitation_force_n, max_transmitted_force_n : float
        Force limits (N) for the excitation-force models (Prev:BEM, IECM, SBEM:EF) and the
        transmitted-force model (SBEM:TF).
    max_speed_mps : float
        Top speed v_max (m/s).
    terrain_frequency_cpm : float
        Prev:BEM's estimated maximum terrain frequency (cycles per metre).
    max_accel_mps2, max_decel_mps2, max_jerk_mps3 : float
        Planning limits: acceleration (m/s^2), deceleration as a positive number (m/s^2) and
        jerk (m/s^3). ``max_jerk_mps3`` may be ``inf`` only when set from code (the command
        line's ``--max-jerk inf``), never in a file.
    max_lateral_accel_mps2 : float or None
        Largest lateral acceleration v^2 kappa in turns (m/s^2); None: no such limit.
    track_width_m, cg_height_m : float or None
        Track width t and centre-of-gravity height h_cg (m), given together: the static
        rollover threshold g t / (2 h_cg) caps the lateral acceleration too.
    friction_coefficient : float or None
        Tyre-ground friction coefficient mu (-): the friction circle
        (a + g sin theta)^2 + (v^2 kappa)^2 <= (mu g cos theta)^2.
    mass_kg, max_power_w : float or None
        Mass of the whole vehicle (kg, at least ``quarter_mass_kg``) and its largest drive
        power at the wheels (W), given together: m (a + g sin theta) v <= P.
    min_turn_radius_m : float or None
        The smallest radius (m) the vehicle turns in, at full lock: a stretch of the path
        sharper than it (a reversal always is) cannot be driven in one sweep and is planned
        at a crawl, :data:`~profileopt.defaults.CRAWL_SPEED_MPS`, with a note naming where
        (:func:`profileopt.physics.motion.turn_speed_cap_mps`). It is kept with the lateral
        limit (``max_lateral_accel_mps2``, or ``track_width_m`` and ``cg_height_m``), which a
        vehicle file giving it must give too; without one the turn limits are off. None: no
        turning circle (a skid-steer vehicle that turns on the spot).
    name : str
        Where the vehicle came from (a bundled name or a path); not a file key.
    """

    quarter_mass_kg: float
    ground_clearance_m: float
    wheel_radius_m: float
    natural_frequency_radps: float
    damping_ratio: float
    confidence: float
    max_excitation_force_n: float
    max_transmitted_force_n: float
    max_speed_mps: float
    terrain_frequency_cpm: float
    max_accel_mps2: float
    max_decel_mps2: float
    max_jerk_mps3: float
    max_lateral_accel_mps2: float | None = None
    track_width_m: float | None = None
    cg_height_m: float | None = None
    friction_coefficient: float | None = None
    mass_kg: float | None = None
    max_power_w: float | None = None
    min_turn_radius_m: float | None = None
    name: str = dataclasses.field(default="", compare=False)

    def __post_init__(self) -> None:
        where = self.name or "Vehicle"
        for key, (unit, what) in {**_UNITS, **_OPTIONAL_UNITS}.items():
            value = getattr(self, key)
            if value is None and key in _OPTIONAL_UNITS:
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise InputError(
                    f"{where}: key '{key}' = {value!r} is not a number; "
                    f"give the {what} as a number in {unit}"
                )
            lo, hi = PLAUSIBLE_RANGES[key]
            try:
                value = float(value)
            except OverflowError:  # an integer too large for a float
                raise InputError(
                    f"{where}: key '{key}' = a {len(str(abs(value)))}-digit integer is outside {lo:g} to {hi:g} "
                    f"{unit}, the range of a ground vehicle's {what}; check the value and its unit"
                ) from None
            object.__setattr__(self, key, value)
            # Only the jerk limit may be switched off (inf), and only from code or the command
            # line: load_vehicle refuses non-finite values in a file.
            infinite_ok = key == "max_jerk_mps3" and value == math.inf
            if not (math.isfinite(value) or infinite_ok) or not value > 0:
                raise InputError(
                    f"{where}: key '{key}' = {value!r} is not allowed; "
                    f"the {what} must be a finite number > 0 in {unit}"
                )
            if key != "confidence" and not infinite_ok and not lo <= value <= hi:
                raise InputError(
                    f"{where}: key '{key}' = {value:g} {unit} is outside {lo:g} to {hi:g} {unit}, the range of "
                    f"a ground vehicle's {what}; check the value and its unit"
                )
        if not 0.5 < self.confidence < 1.0:
            raise InputError(
                f"{where}: key 'confidence' = {self.confidence!r} is outside (0.5, 1); "
                "give the probability Pe that e <= e_max, for example 0.999999"
            )
        for first, second in _PAIRED_KEYS:
            if (getattr(self, first) is None) != (getattr(self, second) is None):
                given, absent = (first, second) if getattr(self, second) is None else (second, first)
                unit, what = _OPTIONAL_UNITS[absent]
                raise InputError(f"{where}: key '{given}' needs key '{absent}' as well; add the {what} in {unit}, "
                                 f"or remove '{given}'")
        if self.mass_kg is not None and self.mass_kg < self.quarter_mass_kg:
            raise InputError(f"{where}: key 'mass_kg' = {self.mass_kg:g} kg is less than quarter_mass_kg = "
                             f"{self.quarter_mass_kg:g} kg; give the mass of the whole vehicle")

    # Quarter-car constants (docs/paper-notes.md): k = m wn^2, c = 2 zeta m wn.
    @property
    def spring_n_per_m(self) -> float:
        """Suspension stiffness k = m wn^2 (N/m)."""
        return self.quarter_mass_kg * self.natural_frequency_radps**2

    @property
    def damping_ns_per_m(self) -> float:
        """Suspension damping c = 2 zeta m wn (N s/m)."""
        return 2.0 * self.damping_ratio * self.quarter_mass_kg * self.natural_frequency_radps

    def replace(self, **changes: float) -> "Vehicle":
        """A copy with some values changed (validated again); unknown keys raise ``TypeError``.

        Parameters
        ----------
        **changes : float
            New values of fields, by name (e.g. ``max_jerk_mps3=2.0``), in the units of the
            field.

        Returns
        -------
        Vehicle
            A new vehicle; this one is unchanged.

        Raises
        ------
        InputError
            A new value is not valid (see :class:`Vehicle`).
        """
        return dataclasses.replace(self, **changes)


def _bundled_dirs() -> list:
    dirs = []
    try:
        dirs.append(resources.files("profileopt.models"))
    except ModuleNotFoundError:  # pragma: no cover - only when the package is broken
        pass
    checkout = Path(__file__).resolve().parents[2] / "models"  # the top-level models/ of a checkout
    if checkout.is_dir():
        dirs.append(checkout)
    return dirs


def bundled_vehicles() -> list[str]:
    """Names of the bundled vehicle files, for example ``["atv", "atv-resonant"]``."""
    names: set[str] = set()
    for d in _bundled_dirs():
        for entry in d.iterdir():
            if entry.name.endswith(".toml"):
                names.add(entry.name[: -len(".toml")])
    return sorted(names)


def names_vehicle_file(name_or_path: str | Path) -> bool:
    """Whether :func:`load_vehicle` reads ``name_or_path`` as a file rather than a bundled
    name: a :class:`~pathlib.Path`, or text ending in ``.toml`` or holding a folder separator.

    Parameters
    ----------
    name_or_path : str or pathlib.Path
        What :func:`load_vehicle` is given.

    Returns
    -------
    bool
    """
    raw = str(name_or_path)
    return isinstance(name_or_path, Path) or raw.endswith(".toml") or "/" in raw or "\\" in raw


def vehicle_reference(vehicle: Vehicle) -> str:
    """How to load ``vehicle`` again: its bundled name, or the path of its file.

    Written into a profile's settings line so that ``profileopt verify`` checks a plan with
    the vehicle it was planned for.

    Parameters
    ----------
    vehicle : Vehicle
        A vehicle, usually from :func:`load_vehicle`.

    Returns
    -------
    str
        The bundled name (e.g. ``"atv"``) if ``vehicle`` was loaded from a bundled file,
        else the path of its file; ``""`` for a vehicle not loaded from a file.
    """
    if not vehicle.name:
        return ""
    path = Path(vehicle.name)
    for d in _bundled_dirs():
        if path.parent == Path(str(d)) and path.suffix == ".toml":
            return path.stem
    return str(path)


def load_vehicle(name_or_path: str | Path) -> Vehicle:
    """Load a vehicle by bundled name (``"atv"``) or from a TOML file path.

    Parameters
    ----------
    name_or_path : str or pathlib.Path
        A bundled name (see :func:`bundled_vehicles`) or the path of a ``.toml`` file.

    Returns
    -------
    Vehicle
        The validated, frozen vehicle.

    Raises
    ------
    InputError
        The file is missing or unreadable, is not valid TOML, misses a key, has an unknown
        key, or a value of the wrong type or out of range. The message names the file, the
        key, the value and the unit expected.
    """
    text, where = _read_vehicle_text(name_or_path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{where}: not valid TOML ({exc}); fix the syntax at that line") from None
    unknown = sorted(set(data) - set(_UNITS) - set(_OPTIONAL_UNITS))
    if unknown:
        raise InputError(
            f"{where}: unknown key '{unknown[0]}'; a vehicle file has the keys "
            + ", ".join(_UNITS) + " and optionally " + ", ".join(_OPTIONAL_UNITS)
        )
    missing = [k for k in _UNITS if k not in data]
    if missing:
        unit, what = _UNITS[missing[0]]
        raise InputError(f"{where}: missing key '{missing[0]}'; add the {what} in {unit}")
    for key, value in data.items():
        if isinstance(value, float) and not math.isfinite(value):
            unit, what = {**_UNITS, **_OPTIONAL_UNITS}[key]
            raise InputError(
                f"{where}: key '{key}' = {value!r} is not finite; give the {what} as a finite "
                f"number > 0 in {unit}"
            )
    if "min_turn_radius_m" in data and not any(key in data for key in _LATERAL_KEYS):
        raise InputError(f"{where}: key 'min_turn_radius_m' needs a lateral acceleration limit as well (the "
                         "turning circle is kept by the limit of turns); add 'max_lateral_accel_mps2' in m/s^2 (or "
                         "'track_width_m' and 'cg_height_m'), or remove 'min_turn_radius_m'")
    return Vehicle(**data, name=where)


def _read_vehicle_text(name_or_path: str | Path) -> tuple[str, str]:
    raw = str(name_or_path)
    if not names_vehicle_file(name_or_path):
        names = bundled_vehicles()
        if raw in names:  # a name only (never a path the system is asked about: 5,000 characters, NUL)
            entry = next(d / f"{raw}.toml" for d in _bundled_dirs() if (d / f"{raw}.toml").is_file())
            return _read_vehicle_file(entry), str(entry)
        shown = raw if len(raw) <= 60 else raw[:60] + "..."
        raise InputError(
            f"vehicle {shown!r}: no bundled vehicle of that name; use one of "
            f"{', '.join(names)} or the path of a .toml file"
        )
    path = Path(raw)
    return _read_vehicle_file(path), str(path)


def _read_vehicle_file(path: Path) -> str:
    # a regular file of at most MAX_VEHICLE_BYTES (not /dev/zero, not a FIFO), its lines ending
    # at \n as in route and profile files (a byte-order mark is accepted)
    from ..io import inputs
    from ..io.table import read_text

    return read_text(path, "vehicle file", max_bytes=inputs.MAX_VEHICLE_BYTES)


def require_vehicle(value: object, where: str) -> Vehicle:
    """``value`` if it is a :class:`Vehicle`; else one line saying what was given and what to give.

    The mistakes made on the way (issue 31): a vehicle's name where a Vehicle is expected, or a
    number there (arguments swapped with ``e_max_m`` or a speed).

    Parameters
    ----------
    value : object
        What was passed as the vehicle.
    where : str
        The function or class it was passed to, for the message.

    Returns
    -------
    Vehicle

    Raises
    ------
    InputError
        ``value`` is not a Vehicle.
    """
    if isinstance(value, Vehicle):
        return value
    if value is None:
        raise InputError(f"{where}: no vehicle was given; give one: profileopt.load_vehicle('atv')")
    if isinstance(value, (str, Path)):
        raise InputError(f"{where}: vehicle = {str(value)!r} is a name or a file; give a Vehicle: "
                         f"profileopt.load_vehicle({str(value)!r})")
    if isinstance(value, (int, float)) or hasattr(value, "shape"):  # a number, an array, a CasADi symbol
        raise InputError(f"{where}: vehicle = {value!r} is a {type(value).__name__}, where a Vehicle goes: are two "
                         "arguments swapped (e_max_m, a speed)? Give the vehicle as profileopt.load_vehicle('atv')")
    raise InputError(f"{where}: vehicle is a {type(value).__name__}; give a Vehicle: profileopt.load_vehicle('atv')")
