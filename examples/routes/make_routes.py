"""Make the bundled example routes of ``examples/routes/`` (seeded, so byte-for-byte
reproducible).

Run from anywhere::

    python examples/routes/make_routes.py              # all routes, beside this script
    python examples/routes/make_routes.py --out DIR    # somewhere else
    python examples/routes/make_routes.py --real PATH  # real data from PATH (default
                                                       # data/real of this repository)

Every route is a CSV file: a ``#`` comment block saying what the route is and how it was
made, then the header ``s,z`` (or ``s,z,speed_limit``): distance along the path s (m),
elevation z (m) and, where present, a speed limit (m/s) at that sample; or ``x,y,z``, a
3-D polyline (m) whose turns count too (mojstrovka.csv). The summaries
below are per 5 m segment (the planner's default), RI detrended with h = 0.1 m (both
bundled vehicles); "first" and "largest" are the allowable speeds of NOTES.md ("Which
root"), SBEM:TF model. The script prints them again when it runs.

Synthetic routes (profileopt.terrain.synthetic, 0.05 m spacing)
-------------------------------------------------------
``trail.csv`` (2000 m, for ``atv``): one random ISO 8608 profile whose class changes
along the trail, joined over 10 m without steps. RI of the 5 m segments and the atv's
"first" allowable speed (one band only: the atv is well damped)::

    0-400 m     B gravel road   RI 0.009-0.037   20 m/s (v_max)
    400-700 m   C               RI 0.016-0.075   20 m/s
    700-1000 m  D               RI 0.034-0.162   13.4-20 m/s
    1000-1250 m E               RI 0.080-0.329   6.8-20 m/s
    1250-1450 m F rocky         RI 0.147-0.492   4.5-14.4 m/s
    1450-1700 m D               RI 0.044-0.135   15.4-20 m/s
    1700-2000 m B gravel road   RI 0.009-0.047   20 m/s

``washboard.csv`` (525 m, for ``atv-resonant``, wn = 6 rad/s, zeta = 0.1): class A
ground (no force limit below v_max = 20 m/s) with a washboard of amplitude 0.04 m and
wavelength 2/3 m (1.5 cycles/m, the paper's terrain frequency) from 150 to 300 m:
A / (sqrt(2) h) = 0.283, measured 0.280-0.284 per segment. Its SBEM:TF bands are
[0, 0.32] and [0.53, 3.37..3.45] m/s: "first" 0.32 m/s, "largest" about 3.4 m/s, so a
vehicle that reaches the upper band on the run-in crosses ten times faster. From 350 to
375 m a rough corrugation (amplitude 0.071 m, wavelength 1 m, RI 0.495) leaves only
[0, 0.28] m/s, so the vehicle must drop below resonance again on the smooth 50 m before
it; then a 150 m run-out to the end (where the planner stops)::

    0-150 m     run-in (class A)        RI 0.005-0.017   band [0, 20]
    150-300 m   washboard A = 0.04 m    RI 0.280-0.284   bands [0, 0.32] + [0.53, 3.37..3.45]
    300-350 m   smooth (class A)        RI 0.008-0.014   band [0, 20]
    350-375 m   rough A = 0.071 m       RI 0.494-0.496   band [0, 0.28]
    375-525 m   run-out (class A)       RI 0.005-0.020   band [0, 20]

(The segment RI of a sinusoid is a little below A / (sqrt(2) h) because each segment's
least-squares line takes out part of it: by 1 - 6 / (pi^2 n^2) in variance over n whole
periods that start at zero height.)

``curb.csv`` (200 m, for ``atv``): class B ground (RI 0.009-0.034), a 0.15 m curb up at
102.5 m and down again at 152.5 m, each in the middle of a 5 m segment (RI 0.385 and
0.372, atv "first" 5.8 and 6.0 m/s). A step exactly on a segment boundary would fall
between two segments, each flat, and would not raise any segment's RI. Column
``speed_limit``: 8 m/s from 40 to 80 m, 12 m/s elsewhere.

Real terrain (copied at the source spacing when the data folder exists)
-----------------------------------------------------------------------
``krc_rms_{1in,2in,4in}.csv`` (504.75 m, 0.05 m): the Keweenaw Research Center RMS ride
courses from Project Chrono's OpenCRG files (BSD-3-Clause): 100 m flat, 304.8 m rough,
flat run-out. Segment RI on the rough part (100-400 m): 1 in 0.041-0.429, 2 in
0.090-0.666, 4 in 0.104-1.300 (atv "first" down to 5.2, 3.3 and 1.7 m/s).
``iri_road.csv`` (544 m, 0.25 m): a measured road profile from michalsorel/iri (MIT),
distance shifted to start at 0, absolute elevations kept. Segment RI 0.004-0.050.
``mojstrovka.csv`` (2701 m, 0.5 m, columns ``x,y,z``): a GPS track (184 points, about
10 m apart) of a mountain trail below Mojstrovka (Julian Alps) from tkrajina/gpxpy
(Apache-2.0): up from about 1625 m to 2040 m and back (smoothed elevations). GPS measures the path's turns and
grade, not the ground's roughness: the elevation is smoothed over about 50 m, so the RI is
near zero (segment RI up to 0.06). Grade (10 m scale) median 29 %, 90th percentile 52 %,
up to 62 %. Turns (profileopt.terrain.geometry.smooth_path): with a 3 m path tolerance the median
radius is 70 m, the 1st percentile 1.9 m (switchbacks), the smallest 0.1 m where the GPS
track doubles back (s = 2594 m); with the default 0.1 m the polyline's corners read as
radii of centimetres.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import xml.etree.ElementTree as ElementTree
from pathlib import Path
from typing import Sequence

import numpy as np

from profileopt import InputError, load_vehicle, speed_bands
from profileopt.terrain.geometry import path_grade_rad, smooth_path
from profileopt.terrain.ground_track import smooth_track_elevations
from profileopt.io import atomic_write, read_opencrg, read_xy_profile
from profileopt.terrain.synthetic import iso8608_profile, iso8608_sections, step, washboard
from profileopt.core.stations import segment_samples
from profileopt.terrain.roughness import segment_roughness_index

HERE = Path(__file__).resolve().parent
#: examples/routes -> repository -> data/real (the measured terrain bundled with it)
DEFAULT_REAL = HERE.parents[1] / "data" / "real"
SPACING_M = 0.05  # synthetic sample spacing (m)
SEGMENT_M = 5.0  # the planner's default segment length (m), used for the summaries
COMMAND = "python examples/routes/make_routes.py"

#: Trail sections in driving order: (ISO 8608 class, length in m, label).
TRAIL = [
    ("B", 400.0, "gravel road"),
    ("C", 300.0, ""),
    ("D", 300.0, ""),
    ("E", 250.0, ""),
    ("F", 200.0, "rocky"),
    ("D", 250.0, ""),
    ("B", 300.0, "gravel road"),
]
#: WGS 84 semi-major axis a (m) and flattening f (NIMA TR8350.2, 3rd ed., 2000, table 3.1).
WGS84_A_M = 6378137.0
WGS84_F = 1 / 298.257223563
MOJSTROVKA_SPACING_M = 0.5  # resampled spacing of the GPS route (m)
#: Length scale (m) over which the GPS elevations are smoothed: about 5 GPS points.
MOJSTROVKA_Z_SCALE_M = 50.0
#: Grade scale (m) of the summaries: twice the planner's default 5 m roughness window.
GRADE_SCALE_M = 10.0
#: Path tolerances (m) of the turn summary: profileopt's default and one for GPS noise.
SUMMARY_TOLERANCES_M = (0.1, 3.0)
TRAIL_SEED = 8608
WASHBOARD_SEED = 8609
CURB_SEED = 8610


@dataclasses.dataclass(frozen=True)
class Section:
    """A stretch of a route to summarise: [start_m, end_m) and what it is."""

    start_m: float
    end_m: float
    label: str


@dataclasses.dataclass(frozen=True)
class BundledRoute:
    """One route file: samples (m, m, m/s), comment lines and sections to summarise."""

    name: str
    vehicle: str
    comments: list[str]
    s_m: np.ndarray
    z_m: np.ndarray
    sections: list[Section]
    speed_limit_mps: np.ndarray | None = None
    s_format: str = "%.4f"
    z_format: str = "%.5f"
    x_m: np.ndarray | None = None  # given: the file has columns x,y,z (s is then not written)
    y_m: np.ndarray | None = None


def rounded(route: BundledRoute) -> tuple[np.ndarray, np.ndarray]:
    """The (s, z) a reader of the CSV gets back (m): the values as written (for an x,y,z
    route, s is the cumulative horizontal distance of the written x, y, as read_route has it)."""
    if route.x_m is not None and route.y_m is not None:
        x, y = (np.array([float(route.s_format % v) for v in c]) for c in (route.x_m, route.y_m))
        s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    else:
        s = np.array([float(route.s_format % x) for x in route.s_m])
    z = np.array([float(route.z_format % x) for x in route.z_m])
    return s, z


def segment_ri(s_m: np.ndarray, z_m: np.ndarray, clearance_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Start (m) and RI of each SEGMENT_M segment from s = 0: s_i <= s < s_i + SEGMENT_M."""
    edges = np.arange(s_m[0], s_m[-1], SEGMENT_M)
    starts, _ = segment_samples(s_m, np.append(edges, s_m[-1]))
    return edges, segment_roughness_index(s_m, z_m, starts, clearance_m)


def summary(route: BundledRoute) -> list[str]:
    """One line per section: RI range of its segments and the SBEM:TF allowable speeds."""
    vehicle = load_vehicle(route.vehicle)
    s, z = rounded(route)
    edges, ri = segment_ri(s, z, vehicle.ground_clearance_m)
    lines = []
    for sec in route.sections:
        inside = (edges >= sec.start_m - 1e-9) & (edges + SEGMENT_M <= sec.end_m + 1e-9)
        r = ri[inside]
        bands = speed_bands(np.array([r.min(), r.max()]), vehicle)
        first = bands.first()
        shown = []
        for row in range(2):
            shown.append(" + ".join(
                f"[{lo:.2f}, {hi:.2f}]"
                for lo, hi in zip(bands.lower_mps[row, : bands.count[row]], bands.upper_mps[row, : bands.count[row]])
            ) or "none")
        lines.append(
            f"{sec.start_m:g}-{sec.end_m:g} m {sec.label}: RI {r.min():.3f}-{r.max():.3f}; "
            f"{route.vehicle} SBEM:TF bands {shown[0]} (smoothest) to {shown[1]} (roughest), "
            f"first {first.min():.2f}-{first.max():.2f} m/s"
        )
    return lines + geometry_summary(route)


def geometry_summary(route: BundledRoute) -> list[str]:
    """For an x,y,z route: its grade and its tightest turns (profileopt.terrain.geometry)."""
    if route.x_m is None or route.y_m is None:
        return []
    s, z = rounded(route)
    grade = np.abs(np.tan(path_grade_rad(s, z, scale_m=GRADE_SCALE_M)))
    lines = [f"grade ({GRADE_SCALE_M:g} m scale): median {100 * np.median(grade):.0f} %, "
             f"90th percentile {100 * np.percentile(grade, 90):.0f} %, largest {100 * grade.max():.0f} %"]
    x, y = (np.array([float(route.s_format % v) for v in c]) for c in (route.x_m, route.y_m))  # as written
    for tolerance in SUMMARY_TOLERANCES_M:
        kappa = np.abs(smooth_path(x, y, tolerance_m=tolerance).curvature_1pm)
        lines.append(f"turn radius (path tolerance {tolerance:g} m): smallest {1 / kappa.max():.2g} m at "
                     f"s = {s[np.argmax(kappa)]:.0f} m, 1st percentile {1 / np.percentile(kappa, 99):.1f} m, "
                     f"median {1 / np.median(kappa):.0f} m")
    return lines


def trail() -> BundledRoute:
    """About 2 km of trail built from ISO 8608 classes B..F (for the ``atv``)."""
    s, z = iso8608_sections([(c, n) for c, n, _ in TRAIL], SPACING_M, TRAIL_SEED, transition_m=10.0)
    ends = np.cumsum([n for _, n, _ in TRAIL])
    sections = [
        Section(end - n, end, f"class {c}" + (f" ({label})" if label else ""))
        for (c, n, label), end in zip(TRAIL, ends)
    ]
    comments = [
        "trail.csv: a 2 km off-road trail for the bundled 'atv' vehicle (profileopt example route).",
        f"Made by `{COMMAND}`: profileopt.terrain.synthetic.iso8608_sections(seed={TRAIL_SEED},",
        "transition_m=10, n from 0.011 to 4 cycles/m): one random ISO 8608 profile, Gd(n) =",
        "Gd(n0) (n/n0)^-2, whose road class changes along the trail (raised-cosine joins of 10 m).",
        "Sections: " + ", ".join(f"{sec.start_m:g}-{sec.end_m:g} m {sec.label}" for sec in sections) + ".",
        "Units: s = distance along the path (m), z = elevation (m); a sample every 0.05 m.",
    ]
    return BundledRoute("trail.csv", "atv", comments, s, z, sections)


def washboard_route() -> BundledRoute:
    """Run-in, washboard, smooth gap, rough corrugation, run-out (for ``atv-resonant``)."""
    length = 525.0
    s, z = iso8608_profile("A", length, SPACING_M, WASHBOARD_SEED)
    z = z + washboard(s, 0.04, 2.0 / 3.0, start_m=150.0, end_m=300.0)
    z = z + washboard(s, 0.071, 1.0, start_m=350.0, end_m=375.0)
    sections = [
        Section(0.0, 150.0, "run-in (class A)"),
        Section(150.0, 300.0, "washboard (A = 0.04 m, 1.5 cycles/m)"),
        Section(300.0, 350.0, "smooth (class A)"),
        Section(350.0, 375.0, "rough corrugation (A = 0.071 m, 1 cycle/m)"),
        Section(375.0, length, "run-out (class A)"),
    ]
    comments = [
        "washboard.csv: a washboard that the bundled 'atv-resonant' vehicle (wn = 6 rad/s,",
        "zeta = 0.1) crosses fastest above its suspension resonance (profileopt example route).",
        f"Made by `{COMMAND}`: ISO 8608 class A ground (profileopt.terrain.synthetic.iso8608_profile,",
        f"seed={WASHBOARD_SEED}) plus profileopt.terrain.synthetic.washboard sinusoids: 150-300 m amplitude",
        "0.04 m, wavelength 2/3 m (RI = A / (sqrt(2) h) = 0.283 with h = 0.1 m: SBEM:TF bands",
        "[0, 0.32] and [0.53, ~3.4] m/s); 350-375 m amplitude 0.071 m, wavelength 1 m (RI 0.495",
        "per detrended 5 m segment: only [0, 0.28] m/s), so the vehicle must slow below resonance on the smooth ground",
        "300-350 m; 375-525 m run-out to the end.",
        "Units: s = distance along the path (m), z = elevation (m); a sample every 0.05 m.",
    ]
    return BundledRoute("washboard.csv", "atv-resonant", comments, s, z, sections)


def curb() -> BundledRoute:
    """200 m of class B ground with a curb up and down and a speed-limit zone."""
    s, z = iso8608_profile("B", 200.0, SPACING_M, CURB_SEED)
    z = z + step(s, 102.5, 0.15) + step(s, 152.5, -0.15)
    limit = np.where((s >= 40.0) & (s < 80.0), 8.0, 12.0)
    sections = [
        Section(0.0, 100.0, "class B"),
        Section(100.0, 105.0, "curb up 0.15 m at 102.5 m"),
        Section(105.0, 150.0, "class B, on the curb"),
        Section(150.0, 155.0, "curb down 0.15 m at 152.5 m"),
        Section(155.0, 200.0, "class B"),
    ]
    comments = [
        "curb.csv: smooth ground with a 0.15 m curb, for the bundled 'atv' vehicle",
        "(profileopt example route).",
        f"Made by `{COMMAND}`: ISO 8608 class B ground (profileopt.terrain.synthetic.iso8608_profile,",
        f"seed={CURB_SEED}) plus profileopt.terrain.synthetic.step: up 0.15 m at s = 102.5 m, down",
        "0.15 m at s = 152.5 m, each in the middle of a 5 m segment (a step exactly on a",
        "segment boundary would leave both segments flat and raise no segment's RI).",
        "speed_limit: 8 m/s for 40 <= s < 80 m, 12 m/s elsewhere.",
        "Units: s = distance along the path (m), z = elevation (m), speed_limit (m/s);",
        "a sample every 0.05 m.",
    ]
    return BundledRoute("curb.csv", "atv", comments, s, z, sections, speed_limit_mps=limit)


def krc_course(real: Path, nominal_in: int) -> BundledRoute:
    """A Keweenaw Research Center RMS ride course (Project Chrono OpenCRG file, BSD-3)."""
    source = f"data/vehicle/terrain/crg_roads/detrended_rms_course_{nominal_in}in.crg"
    s, z = read_opencrg(real / "krc-rms-courses" / Path(source).name)
    rough = (s >= 100.0) & (s <= 404.8)
    comments = [
        f"krc_rms_{nominal_in}in.csv: the Keweenaw Research Center 'RMS {nominal_in} in' off-road ride",
        "course (measured terrain, detrended): 100 m flat run-in, 304.8 m rough, flat run-out.",
        f"Source: Project Chrono, https://github.com/projectchrono/chrono, {source}",
        "(CRG calculated from KRC data), BSD-3-Clause licence, Copyright (c) 2016 Project Chrono",
        "Development Team; see the LICENSE of data/real/krc-rms-courses/.",
        f"Converted by `{COMMAND}` from data/real/ with profileopt.io.read_opencrg",
        "(the middle of the 3 identical lateral tracks). RMS elevation of 100-404.8 m:",
        f"{1000 * z[rough].std():.1f} mm (nominal {nominal_in} in = {25.4 * nominal_in:.1f} mm).",
        "Units: s = distance along the reference line (m), z = elevation (m); a sample every 0.05 m.",
    ]
    sections = [Section(0.0, 100.0, "flat run-in"), Section(100.0, 400.0, "rough course"),
                Section(405.0, 500.0, "flat run-out")]
    return BundledRoute(f"krc_rms_{nominal_in}in.csv", "atv", comments, s, z, sections)


def iri_road(real: Path) -> BundledRoute:
    """A measured road profile (michalsorel/iri, MIT), shifted to start at s = 0."""
    s, z = read_xy_profile(real / "iri-road-profile" / "profile_1.txt")
    offset = float(s[0])
    comments = [
        "iri_road.csv: a measured road longitudinal profile (absolute elevations, m).",
        "Source: michalsorel/iri, https://github.com/michalsorel/iri, profile_1.txt, MIT licence,",
        "Copyright (c) 2023 Michal Sorel, Filip Sroubek; see the LICENSE of",
        "data/real/iri-road-profile/.",
        f"Converted by `{COMMAND}` from data/real/ with profileopt.io.read_xy_profile;",
        f"distance shifted by -{offset:g} m so that the route starts at s = 0.",
        "Units: s = distance along the path (m), z = elevation (m); a sample every 0.25 m.",
    ]
    s = s - offset
    sections = [Section(0.0, 5.0 * np.floor(s[-1] / 5.0), "whole road")]
    return BundledRoute("iri_road.csv", "atv", comments, s, z, sections)


def mojstrovka(real: Path) -> BundledRoute:
    """A GPS track of a mountain trail (tkrajina/gpxpy test file, Apache-2.0) as x,y,z."""
    source = real / "gpx-tracks" / "Mojstrovka.gpx"
    root = ElementTree.parse(source).getroot()
    ns = {"gpx": root.tag[1:].split("}")[0]}  # the GPX namespace the file declares (1.0 here)
    points = np.array([(float(p.get("lat")), float(p.get("lon")), float(p.find("gpx:ele", ns).text))
                       for p in root.iterfind(".//gpx:trkpt", ns)])
    lat, lon = np.radians(points[:, 0]), np.radians(points[:, 1])
    # local east-north tangent plane at the track's mean position on the WGS 84 ellipsoid:
    # meridional radius M = a (1 - e^2) / w^3 and prime-vertical radius N = a / w, with
    # w = sqrt(1 - e^2 sin^2 lat0) (e.g. Torge and Mueller, Geodesy, 4th ed., 2012), then
    # east = N cos(lat0) (lon - lon0), north = M (lat - lat0). Against the exact tangent plane
    # (ECEF to ENU) this is off by 2.4 cm at most over the track's 0.5 km from the centre.
    lat0, lon0 = float(lat.mean()), float(lon.mean())
    e2 = WGS84_F * (2 - WGS84_F)
    w = math.sqrt(1 - e2 * math.sin(lat0) ** 2)
    east = WGS84_A_M / w * math.cos(lat0) * (lon - lon0)
    north = WGS84_A_M * (1 - e2) / w**3 * (lat - lat0)
    keep = np.concatenate([[True], np.hypot(np.diff(east), np.diff(north)) > 0])  # drop repeated points
    east, north, ele = east[keep], north[keep], points[keep, 2]
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(east), np.diff(north)))])
    # A reading equal to the one before it, to the 0.1 mm the log keeps, is a frozen altimeter
    # (the log holds 1942.4904 m for 7 points over 80 m, then drops 69 m in 28 m): only the
    # first of such a run is a measurement, the others get a weight of 1e-6 in the fit below.
    frozen = np.concatenate([[False], np.diff(ele) == 0])
    # GPS elevations are noisy by metres: a smoothing spline of z over s, lam = (n / L) 50^4,
    # smooths over about 50 m (5 points), the frozen readings weighted 1e-6 (as profileopt route does)
    z_spline = smooth_track_elevations(s, ele, scale_m=MOJSTROVKA_Z_SCALE_M)
    deviation = (z_spline(s) - ele)[~frozen]
    # each GPS segment cut into equal pieces of at most 0.5 m: the GPS points are kept, so the
    # chord lengths that read_route sums are the track's horizontal length and z(s) is kept
    # (cutting a corner with a 0.5 m grid would shorten s there, which reads as roughness)
    pieces = np.ceil(np.diff(s) / MOJSTROVKA_SPACING_M).astype(int)
    s_new = np.append(np.repeat(s[:-1], pieces) + np.concatenate([np.arange(n) / n for n in pieces])
                      * np.repeat(np.diff(s), pieces), s[-1])
    x, y, z = np.interp(s_new, s, east), np.interp(s_new, s, north), z_spline(s_new)
    top = int(np.argmax(z))
    comments = [
        "mojstrovka.csv: a GPS track of a mountain trail below Mojstrovka (Julian Alps, Slovenia),",
        f"up from {z[0]:.0f} m to {z[top]:.0f} m and back down, {s[-1]:.0f} m: a path with turns and hills.",
        "Source: tkrajina/gpxpy, https://github.com/tkrajina/gpxpy, test_files/Mojstrovka.gpx",
        f"({points.shape[0]} points, median {np.median(np.diff(s)):.0f} m apart), Apache-2.0 licence;",
        "see the LICENSE.txt of data/real/gpx-tracks/.",
        f"Converted by `{COMMAND}` from data/real/: latitude, longitude projected to",
        "local metres on the east-north tangent plane at the track's mean position on the WGS 84",
        "ellipsoid (meridional and prime-vertical radii of curvature; under 3 cm from the exact",
        "tangent plane here, far below GPS noise), x east, y north; repeated points dropped; the",
        f"polyline resampled at {MOJSTROVKA_SPACING_M:g} m (each GPS segment cut into equal pieces of at most",
        f"{MOJSTROVKA_SPACING_M:g} m, linear interpolation: the GPS points are kept, s is the track's length).",
        "GPS measures the path's geometry and its grade, not the ground's roughness: the elevation",
        "is smoothed before resampling (scipy make_smoothing_spline of z over s,",
        f"lam = (n/L) {MOJSTROVKA_Z_SCALE_M:g}^4: smoothing over about {MOJSTROVKA_Z_SCALE_M:g} m; the {int(frozen.sum())} "
        "readings equal to the one before them (a frozen altimeter: 1942.4904 m for 80 m, then a 69 m drop)",
        "are given a weight of 1e-6; it departs from the other GPS elevations by",
        f"{np.sqrt(np.mean(deviation**2)):.1f} m RMS, by up to {np.max(np.abs(deviation)):.0f} m),",
        "so the route's roughness is near zero: plan it to see turns and",
        "hills, not roughness. The GPS path is noisy by metres too: smooth it with a path",
        "tolerance of a few metres (a 0.1 m tolerance reads the noise and the polyline's corners",
        "as sharp turns).",
        f"Units: x, y, z (m); a point every {MOJSTROVKA_SPACING_M:g} m or closer along the path.",
    ]
    sections = [Section(0.0, 5.0 * np.floor(s_new[top] / 5.0), "climb"),
                Section(5.0 * np.ceil(s_new[top] / 5.0), 5.0 * np.floor(s_new[-1] / 5.0), "descent")]
    return BundledRoute("mojstrovka.csv", "atv", comments, s_new, z, sections, x_m=x, y_m=y, z_format="%.4f")


def write(route: BundledRoute, folder: Path) -> Path:
    """Write ``route`` as ``folder / route.name`` (atomically); return the path."""
    if route.x_m is not None and route.y_m is not None:  # a 3-D polyline: x,y,z
        path = folder / route.name
        with atomic_write(path) as handle:
            for line in route.comments:
                handle.write(f"# {line}\n")
            handle.write("x,y,z\n")
            formats = [route.s_format, route.s_format, route.z_format]
            # rounded first, then + 0.0: no -0.0000 in the file
            table = np.column_stack([np.round(c, int(f[2:-1])) + 0.0
                                     for c, f in zip((route.x_m, route.y_m, route.z_m), formats)])
            np.savetxt(handle, table, fmt=formats, delimiter=",")
        return path
    columns = [route.s_m, route.z_m]
    formats = [route.s_format, route.z_format]
    header = "s,z"
    if route.speed_limit_mps is not None:
        columns.append(route.speed_limit_mps)
        formats.append("%.2f")
        header += ",speed_limit"
    path = folder / route.name
    with atomic_write(path) as handle:
        for line in route.comments:
            handle.write(f"# {line}\n")
        handle.write(header + "\n")
        # + 0.0 turns a rounded -0.0 into 0.0
        table = np.column_stack([np.round(c, 5) + 0.0 if f == "%.5f" else c for c, f in zip(columns, formats)])
        np.savetxt(handle, table, fmt=formats, delimiter=",")
    return path


def synthetic_routes() -> list[BundledRoute]:
    """The routes made from profileopt.terrain.synthetic (no data needed)."""
    return [trail(), washboard_route(), curb()]


def real_routes(real: Path) -> list[BundledRoute]:
    """The routes converted from measured terrain in ``real`` (data/real)."""
    return [krc_course(real, 1), krc_course(real, 2), krc_course(real, 4), iri_road(real), mojstrovka(real)]


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=HERE, help="folder for the CSV files, created if missing (default: beside this script)")
    parser.add_argument("--real", type=Path, default=DEFAULT_REAL,
                        help="the folder of measured terrain (default: data/real of this repository)")
    parser.add_argument("--no-real", action="store_true", help="write the synthetic routes only")
    parser.add_argument("--quiet", action="store_true", help="do not print the per-section summaries")
    args = parser.parse_args(argv)

    # before any work: one line, not a traceback after it; a missing folder is created (as
    # 'profileopt figures --out' does)
    if args.out.exists() and not args.out.is_dir():
        print(f"error: --out {args.out}: exists and is not a folder; give a folder path", file=sys.stderr)
        return 2
    try:
        args.out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        print(f"error: --out {args.out}: cannot create the folder ({exc.strerror}); choose another path",
              file=sys.stderr)
        return 2
    routes = synthetic_routes()
    if args.no_real:
        pass
    elif args.real.is_dir():
        routes += real_routes(args.real)
    else:
        print(f"error: {args.real} is not a folder of measured terrain (--real); "
              "pass --no-real to write the synthetic routes only", file=sys.stderr)
        return 2
    for route in routes:
        try:
            path = write(route, args.out)
        except InputError as exc:  # e.g. a folder that cannot be written
            print(f"error: {exc}", file=sys.stderr)
            return 2
        if not args.quiet:
            s, _ = rounded(route)
            print(f"{path} ({s[-1]:g} m, {s.size} samples, {path.stat().st_size / 1e3:.0f} kB, for {route.vehicle})")
            for line in summary(route):
                print("    " + line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
