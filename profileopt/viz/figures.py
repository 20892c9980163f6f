"""The paper's Figs. 1, 5 and 6, rebuilt from the library.

Each ``figure_*`` function returns a :class:`FigureData`: the curves as arrays, with CSV
column names that carry their units, a title and a caption. :func:`write_figure` writes
one as a PNG and as the CSV of its curves; :func:`write_paper_figures` writes all three.

The terrain is built the paper's way (Section 4): 100 sinusoidal profiles with amplitudes
evenly spaced from 0 to 0.1 m, at 1.5 cycles/m for Figs. 5 and 6 and at 1 cycle/m
(2 pi rad/m) for Fig. 1, each RI computed by :func:`~profileopt.terrain.roughness.roughness_index`
from the sampled profile, never from a closed form. Speeds come from
:func:`~profileopt.physics.speeds.allowable_speed`.

The old RI of the paper's reference [11] is not reconstructed (its text is not available,
docs/paper-notes.md), so Fig. 1 shows the paper's new RI (Eq. 1) only and says so.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import numpy as np

from ..core.vehicle import Vehicle, load_vehicle
from ..io.atomic import OutputSet, atomic_path, atomic_write
from ..physics.forces import MODELS
from ..physics.speeds import allowable_speed
from ..progress import NO_PROGRESS, Progress
from ..terrain.roughness import roughness_index
from ..terrain.synthetic import washboard

__all__ = [
    "Curve",
    "FigureData",
    "plot_figure",
    "SinusoidTerrain",
    "sinusoid_terrain",
    "figure_1",
    "figure_5",
    "figure_6",
    "paper_figures",
    "write_figure",
    "write_paper_figures",
    "paper_figure_paths",
    "PAPER_FIGURE_STEMS",
    "PAPER_AMPLITUDES_M",
    "FIG1_FREQUENCY_CPM",
    "FIG1_CLEARANCE_M",
    "TERRAIN_FREQUENCY_CPM",
]

#: The file stems of Figs. 1, 5 and 6 (each written as .png and .csv).
PAPER_FIGURE_STEMS = ("fig1_ri_vs_amplitude", "fig5_allowable_speed", "fig6_resonance")

#: The paper's 100 terrain amplitudes, evenly spaced from 0 to 0.1 m (Section 4, Table 1).
PAPER_AMPLITUDES_M: np.ndarray = np.linspace(0.0, 0.1, 100)
#: Fig. 1's sinusoids: 2 pi rad/m, that is 1 cycle/m (docs/paper-notes.md), and clearance h = 0.1 m.
FIG1_FREQUENCY_CPM = 1.0
FIG1_CLEARANCE_M = 0.1
#: Table 1's terrain distance frequency for Figs. 5 and 6 (cycles/m).
TERRAIN_FREQUENCY_CPM = 1.5
#: Each sampled profile: a whole number of periods, evenly sampled (see sinusoid_terrain).
PERIODS = 10
SAMPLES_PER_PERIOD = 64


@dataclasses.dataclass(frozen=True)
class Curve:
    """One plotted curve and its CSV column.

    Attributes
    ----------
    column : str
        CSV column name, with its unit as a suffix (``"sbem_tf_first_mps"``).
    label : str
        Legend text.
    values : numpy.ndarray, shape (N,)
        The curve's values, in the unit its column names.
    """

    column: str
    label: str
    values: np.ndarray


@dataclasses.dataclass(frozen=True)
class FigureData:
    """The data of one figure: an x array and the curves plotted against it.

    Attributes
    ----------
    stem : str
        File name without extension, e.g. ``"fig5_allowable_speed"``.
    title : str
        Figure title.
    caption : str
        What the figure shows and how it was made (printed under the plot).
    x_label, y_label : str
        Axis labels, with units.
    x : Curve
        The abscissa, shape (N,).
    curves : tuple of Curve
        The plotted curves, each shape (N,).
    extra : tuple of Curve
        Columns written to the CSV but not plotted (e.g. the terrain amplitude, m).
    log_panel : bool
        Add a second panel below with a logarithmic y axis, so that curves near zero
        (Fig. 6's ~0.3 m/s band below resonance) can be told apart.
    """

    stem: str
    title: str
    caption: str
    x_label: str
    y_label: str
    x: Curve
    curves: tuple[Curve, ...]
    extra: tuple[Curve, ...] = ()
    log_panel: bool = False

    @property
    def columns(self) -> tuple[str, ...]:
        """CSV column names, with units: the extra columns, x, then the curves."""
        return tuple(c.column for c in (*self.extra, self.x, *self.curves))

    def table(self) -> np.ndarray:
        """The CSV's numbers, shape (N, len(columns)), in the order of :attr:`columns`."""
        return np.column_stack([c.values for c in (*self.extra, self.x, *self.curves)])

    def curve(self, column: str) -> Curve:
        """The curve (or x, or extra column) called ``column``; ``KeyError`` otherwise.

        Parameters
        ----------
        column : str
            A CSV column name, with its unit, as in :attr:`columns`.

        Returns
        -------
        Curve
        """
        for c in (*self.extra, self.x, *self.curves):
            if c.column == column:
                return c
        raise KeyError(f"{self.stem} has no column {column!r}; it has {', '.join(self.columns)}")


@dataclasses.dataclass(frozen=True)
class SinusoidTerrain:
    """A family of sampled sinusoidal profiles and their roughness indices.

    Attributes
    ----------
    amplitude_m : numpy.ndarray, shape (N,)
        Amplitude A of each profile (m).
    frequency_cpm : float
        Spatial frequency (cycles/m).
    clearance_m : float
        Ground clearance h used for the RI (m).
    positions_m : numpy.ndarray, shape (K,)
        Sample positions along every profile (m).
    ri : numpy.ndarray, shape (N,)
        RI of each profile (Eq. 1), computed from its samples (dimensionless).
    """

    amplitude_m: np.ndarray
    frequency_cpm: float
    clearance_m: float
    positions_m: np.ndarray
    ri: np.ndarray

    def elevations_m(self, i: int) -> np.ndarray:
        """The sampled elevations of profile ``i`` (m), shape (K,).

        Parameters
        ----------
        i : int
            Index of the profile, 0 <= i < N (into :attr:`amplitude_m`).

        Returns
        -------
        numpy.ndarray, shape (K,)
            Elevations (m) of the sinusoid of amplitude ``amplitude_m[i]`` at
            :attr:`positions_m`.
        """
        return washboard(self.positions_m, float(self.amplitude_m[i]), 1.0 / self.frequency_cpm)


def sinusoid_terrain(
    amplitudes_m: np.ndarray,
    frequency_cpm: float,
    clearance_m: float,
    periods: int = PERIODS,
    samples_per_period: int = SAMPLES_PER_PERIOD,
) -> SinusoidTerrain:
    """Sample sinusoids A sin(2 pi f s) and compute the RI of each from its samples.

    Each profile covers a whole number of periods, evenly sampled (the end point, which
    repeats the start, left out), so its sample mean is 0 and its population STD is
    A / sqrt(2) exactly: the RI is that of the sinusoid, not of a partial period.

    The RI is the paper's raw definition (``detrend=False``): the paper computes RI =
    STD(e / h) of the profile as it is (Eq. 1) and these flat sinusoids have no grade to
    remove. Removing the least-squares line would not be neutral here: over a finite
    window a sine correlates with distance, so detrending would lower each RI by a
    fraction of about 6 / (pi^2 n^2) (0.6 % for n = 10 periods) and shift the figures.

    Parameters
    ----------
    amplitudes_m : numpy.ndarray, shape (N,)
        Amplitudes A (m), >= 0.
    frequency_cpm : float
        Spatial frequency f (cycles/m), > 0.
    clearance_m : float
        Ground clearance h (m), > 0.
    periods, samples_per_period : int
        Length of each profile in periods and samples per period (>= 3).

    Returns
    -------
    SinusoidTerrain
    """
    amplitudes = np.asarray(amplitudes_m, dtype=float)
    n_samples = periods * samples_per_period
    positions = np.arange(n_samples) / (samples_per_period * frequency_cpm)
    shape = washboard(positions, 1.0, 1.0 / frequency_cpm)  # unit amplitude; each profile is A * shape
    ri = np.array([
        roughness_index(a * shape, clearance_m, positions_m=positions, detrend=False) for a in amplitudes
    ])
    return SinusoidTerrain(
        amplitude_m=amplitudes,
        frequency_cpm=float(frequency_cpm),
        clearance_m=float(clearance_m),
        positions_m=positions,
        ri=ri,
    )


def _terrain_text(terrain: SinusoidTerrain) -> str:
    return (
        f"{terrain.amplitude_m.size} sinusoidal profiles at {terrain.frequency_cpm:g} cycles/m, "
        f"amplitudes {terrain.amplitude_m.min():g} to {terrain.amplitude_m.max():g} m, "
        f"RI = STD(e/h) of each sampled profile (Eq. 1), h = {terrain.clearance_m:g} m"
    )


def figure_1(amplitudes_m: np.ndarray = PAPER_AMPLITUDES_M) -> FigureData:
    """Fig. 1: the RI of Eq. (1) against the amplitude of a sinusoidal terrain.

    Sinusoids of 2 pi rad/m (1 cycle/m), amplitudes 0 to 0.1 m, h = 0.1 m. For a whole
    number of periods RI = A / (sqrt(2) h), so the line runs from 0 to 0.707. The old RI of
    the paper's reference [11] is not reconstructed (docs/paper-notes.md): only the new RI is shown.

    Parameters
    ----------
    amplitudes_m : numpy.ndarray, shape (N,)
        Terrain amplitudes (m).

    Returns
    -------
    FigureData
        Columns ``amplitude_m`` (x) and ``ri``.
    """
    terrain = sinusoid_terrain(amplitudes_m, FIG1_FREQUENCY_CPM, FIG1_CLEARANCE_M)
    return FigureData(
        stem="fig1_ri_vs_amplitude",
        title="Fig. 1: roughness index of sinusoidal terrain (new RI, Eq. 1, only)",
        caption=(
            _terrain_text(terrain) + ". The old RI of the paper's reference [11] is not "
            "reconstructed (its definition is not available), so only the new RI is shown."
        ),
        x_label="terrain amplitude A (m)",
        y_label="roughness index RI (-)",
        x=Curve("amplitude_m", "terrain amplitude (m)", terrain.amplitude_m),
        curves=(Curve("ri", "new RI = STD(e/h), Eq. (1)", terrain.ri),),
    )


def figure_5(vehicle: Vehicle | None = None, amplitudes_m: np.ndarray = PAPER_AMPLITUDES_M) -> FigureData:
    """Fig. 5: allowable speed of the four models against RI (Table 1 vehicle).

    Parameters
    ----------
    vehicle : Vehicle, optional
        Defaults to the bundled ``atv`` (Table 1).
    amplitudes_m : numpy.ndarray, shape (N,)
        Terrain amplitudes (m) of the sinusoids at 1.5 cycles/m.

    Returns
    -------
    FigureData
        Columns ``amplitude_m``, ``ri`` (x), ``prev_bem_mps``, ``iecm_mps``, ``sbem_ef_mps``,
        ``sbem_tf_mps``. SBEM:TF uses the ``"first"`` semantics; for the Table 1 vehicle the
        force grows monotonically with speed, so ``"first"`` and ``"largest"`` coincide.
    """
    vehicle = vehicle if vehicle is not None else load_vehicle("atv")
    terrain = sinusoid_terrain(amplitudes_m, TERRAIN_FREQUENCY_CPM, vehicle.ground_clearance_m)
    curves = []
    for key, model in MODELS.items():
        label = model.label + (" (the project's reconstruction of the paper's ref. [11])" if key == "prev_bem" else "")
        if key == "sbem_tf":
            label += ' ("first"; = "largest" here, force monotone in speed)'
        speed = allowable_speed(terrain.ri, vehicle, model=key, band="first")
        curves.append(Curve(f"{key}_mps", label, np.asarray(speed, dtype=float)))
    return FigureData(
        stem="fig5_allowable_speed",
        title=f"Fig. 5: allowable speed vs. RI ({_vehicle_text(vehicle)})",
        caption=(
            _terrain_text(terrain) + f". Limits: excitation {vehicle.max_excitation_force_n:g} N, "
            f"transmitted {vehicle.max_transmitted_force_n:g} N, top speed {vehicle.max_speed_mps:g} m/s. "
            "Prev:BEM is the project's reconstruction of [11]. SBEM:EF and SBEM:TF nearly coincide."
        ),
        x_label="roughness index RI (-)",
        y_label="allowable speed (m/s)",
        x=Curve("ri", "roughness index (-)", terrain.ri),
        curves=tuple(curves),
        extra=(Curve("amplitude_m", "terrain amplitude (m)", terrain.amplitude_m),),
    )


def figure_6(vehicle: Vehicle | None = None, amplitudes_m: np.ndarray = PAPER_AMPLITUDES_M) -> FigureData:
    """Fig. 6: SBEM:EF against SBEM:TF for the resonant vehicle, both SBEM:TF semantics.

    Parameters
    ----------
    vehicle : Vehicle, optional
        Defaults to the bundled ``atv-resonant`` (wn = 6 rad/s, zeta = 0.1, limits 1000 N).
    amplitudes_m : numpy.ndarray, shape (N,)
        Terrain amplitudes (m) of the sinusoids at 1.5 cycles/m.

    Returns
    -------
    FigureData
        Columns ``amplitude_m``, ``ri`` (x), ``sbem_ef_mps``, ``sbem_tf_largest_mps`` (the
        largest admissible speed, the root the paper's Newton iteration lands on: it
        reproduces the paper's Fig. 6) and ``sbem_tf_first_mps`` (every speed from rest up
        to it admissible: what a vehicle starting from rest can use).
    """
    vehicle = vehicle if vehicle is not None else load_vehicle("atv-resonant")
    terrain = sinusoid_terrain(amplitudes_m, TERRAIN_FREQUENCY_CPM, vehicle.ground_clearance_m)
    ef = allowable_speed(terrain.ri, vehicle, model="sbem_ef", band="first")
    tf_largest = allowable_speed(terrain.ri, vehicle, model="sbem_tf", band="largest")
    tf_first = allowable_speed(terrain.ri, vehicle, model="sbem_tf", band="first")
    return FigureData(
        stem="fig6_resonance",
        title=f"Fig. 6: allowable speed vs. RI, resonance case ({_vehicle_text(vehicle)})",
        caption=(
            _terrain_text(terrain) + f". Limits: {vehicle.max_excitation_force_n:g} N excitation, "
            f"{vehicle.max_transmitted_force_n:g} N transmitted. SBEM:TF has separate admissible "
            'speed bands below and above resonance: "largest" = highest admissible speed '
            '(the root the paper reports); "first" = highest speed with every speed from rest '
            "up to it admissible. SBEM:EF drops to 0 where even the static force k e_max exceeds the limit."
        ),
        x_label="roughness index RI (-)",
        y_label="allowable speed (m/s)",
        x=Curve("ri", "roughness index (-)", terrain.ri),
        curves=(
            Curve("sbem_ef_mps", "SBEM:EF", np.asarray(ef, dtype=float)),
            Curve("sbem_tf_largest_mps", 'SBEM:TF "largest" (highest admissible speed; paper\'s Fig. 6)',
                  np.asarray(tf_largest, dtype=float)),
            Curve("sbem_tf_first_mps", 'SBEM:TF "first" (all speeds from rest admissible)',
                  np.asarray(tf_first, dtype=float)),
        ),
        extra=(Curve("amplitude_m", "terrain amplitude (m)", terrain.amplitude_m),),
        log_panel=True,
    )


def _vehicle_text(vehicle: Vehicle) -> str:
    name = Path(vehicle.name).stem if vehicle.name else "vehicle"
    return (
        f"{name}: wn = {vehicle.natural_frequency_radps:g} rad/s, "
        f"zeta = {vehicle.damping_ratio:g}"
    )


def paper_figures(vehicle: Vehicle | None = None, resonant_vehicle: Vehicle | None = None) -> tuple[FigureData, ...]:
    """Figs. 1, 5 and 6 (defaults: the bundled ``atv`` and ``atv-resonant`` vehicles).

    Parameters
    ----------
    vehicle : Vehicle, optional
        The vehicle of Fig. 5 (see :func:`figure_5`); defaults to the bundled ``atv``.
    resonant_vehicle : Vehicle, optional
        The vehicle of Fig. 6 (see :func:`figure_6`); defaults to the bundled
        ``atv-resonant``.

    Returns
    -------
    tuple of FigureData
        The data of Figs. 1, 5 and 6, in that order.
    """
    return (figure_1(), figure_5(vehicle), figure_6(resonant_vehicle))


# Line styles that stay apart in grey-scale print too; the "first"/"largest" pair of Fig. 6
# share SBEM:TF's colour and differ in line style and marker.
def write_figure(data: FigureData, out_dir: str | os.PathLike) -> list[Path]:
    """Write ``data`` as ``<stem>.png`` and ``<stem>.csv`` in ``out_dir`` (which must exist).

    Both files go through :func:`profileopt.io.atomic_path` / ``atomic_write``: a failure
    leaves no half-written file. The CSV has one header line (the column names, with
    units) and one row per point, numbers with 17 significant digits (exact round trip).

    Parameters
    ----------
    data : FigureData
        The figure to write; its ``stem`` names the files.
    out_dir : str or os.PathLike
        An existing, writable folder.

    Returns
    -------
    list of pathlib.Path
        The PNG and the CSV written.
    """
    out = Path(out_dir)
    png, csv = out / f"{data.stem}.png", out / f"{data.stem}.csv"
    with atomic_path(png) as tmp:
        plot_figure(data, tmp)
    with atomic_write(csv) as handle:
        handle.write(",".join(data.columns) + "\n")
        for row in data.table():
            handle.write(",".join(f"{v:.17g}" for v in row) + "\n")
    return [png, csv]


def write_paper_figures(
    out_dir: str | os.PathLike,
    vehicle: Vehicle | None = None,
    resonant_vehicle: Vehicle | None = None,
    *,
    progress: Progress = NO_PROGRESS,
) -> list[Path]:
    """Write Figs. 1, 5 and 6 (PNG + CSV each) into ``out_dir`` (which must exist).

    Parameters
    ----------
    out_dir : str or os.PathLike
        An existing, writable folder.
    vehicle : Vehicle, optional
        The vehicle of Fig. 5; defaults to the bundled ``atv``.
    resonant_vehicle : Vehicle, optional
        The vehicle of Fig. 6; defaults to the bundled ``atv-resonant``.
    progress : Progress, default :data:`profileopt.progress.NO_PROGRESS`
        Told each step (computing the curves, drawing each figure).

    Returns
    -------
    list of pathlib.Path
        The six files written, in order.
    """
    progress.expect(1 + len(PAPER_FIGURE_STEMS))
    progress.step("computing the curves of Figs. 1, 5 and 6")
    figures = paper_figures(vehicle, resonant_vehicle)
    written = [Path(out_dir) / f"{data.stem}.{ext}" for data in figures for ext in ("png", "csv")]
    with OutputSet([("", path) for path in written]):  # checked first; all six files or none
        for data in figures:
            progress.step(f"drawing {data.stem}.png")
            write_figure(data, out_dir)
    return written


def paper_figure_paths(out_dir: str | os.PathLike) -> list[Path]:
    """The six files :func:`write_paper_figures` writes into ``out_dir``, in order.

    Parameters
    ----------
    out_dir : str or os.PathLike
        The folder.

    Returns
    -------
    list of pathlib.Path
    """
    return [Path(out_dir) / f"{stem}.{ext}" for stem in PAPER_FIGURE_STEMS for ext in ("png", "csv")]


_STYLES: dict[str, dict] = {
    "ri": dict(color="tab:blue", linestyle="-"),
    "prev_bem_mps": dict(color="tab:gray", linestyle="-."),
    "iecm_mps": dict(color="tab:orange", linestyle="--"),
    "sbem_ef_mps": dict(color="tab:blue", linestyle="-", linewidth=2.5),
    "sbem_tf_mps": dict(color="tab:red", linestyle=":", linewidth=2.5),
    "sbem_tf_largest_mps": dict(color="tab:red", linestyle="--", marker="o", markersize=3),
    "sbem_tf_first_mps": dict(color="tab:purple", linestyle=":", marker="x", markersize=4),
}


def plot_figure(data: FigureData, path: str | Path) -> None:
    """Draw one of the paper's figures (:mod:`profileopt.viz.figures`) as a PNG at ``path``.

    The caller makes ``path`` atomic (:func:`profileopt.viz.figures.write_figure` passes a
    temporary file that it renames into place).

    Parameters
    ----------
    data : FigureData
        The curves, labels and caption of the figure.
    path : str or pathlib.Path
        Output PNG file.
    """
    from matplotlib.figure import Figure

    # A bare matplotlib Figure (object API, no pyplot): it draws with the Agg renderer
    # whatever backend the caller has chosen, opens no window, changes no global state and
    # is freed with the object, so this is safe in scripts, tests, servers and notebooks.
    if data.log_panel:
        fig = Figure(figsize=(8.0, 8.0), layout="constrained")
        ax, ax_log = fig.subplots(2, 1, sharex=True, height_ratios=(3, 2))
    else:
        fig = Figure(figsize=(8.0, 5.6), layout="constrained")
        ax, ax_log = fig.subplots(), None
    for axes in (ax, ax_log):
        if axes is None:
            continue
        for curve in data.curves:
            axes.plot(data.x.values, curve.values, label=curve.label, **_STYLES.get(curve.column, {}))
        axes.set_ylabel(data.y_label)
        axes.set_xlim(left=0.0)
        axes.grid(True, which="both", alpha=0.3)
    ax.set_ylim(bottom=0.0)
    ax.set_title(data.title, fontsize=11)
    ax.legend(loc="best", fontsize=9)
    if ax_log is not None:
        ax_log.set_yscale("log")
        ax_log.set_ylabel(data.y_label + ", log scale")
        ax_log.set_ylim(bottom=0.1)
        ax_log.set_xlabel(data.x_label)
    else:
        ax.set_xlabel(data.x_label)
    fig.get_layout_engine().set(h_pad=0.15)
    fig.supxlabel(data.caption, fontsize=8, wrap=True, x=0.02, ha="left")
    fig.savefig(path, format="png", dpi=120)
