"""The memory a plan needs, estimated before any work, and the ``--max-memory`` check.

``profileopt plan`` (and ``batch``'s rows, and ``drive``, which plans the route offline as its
yardstick) holds at its peak the route's samples, the NLP over its segments, and the exact
simulation the planner drives the plan in before returning it (:mod:`profileopt.planning.gate`),
whose time steps grow with the travel time. Peak resident memory, measured with
``/usr/bin/time -v`` on 18 routes (s,z and x,y,z files, tracks; 0.05 and 0.5 m spacings;
2 to 500 km; smooth, rough and slow; refined and not), fits

    peak = 150 MB + 1.13 kB x samples + 3.6 kB x segments + 0.5 kB x simulation steps

within 25 % but for rough routes whose wheel path has many knots (up to 30 % above it). The
estimate (:func:`estimated_plan_bytes`), made before planning, cannot know the segments a
refinement adds nor the travel time, so it takes :data:`REFINED_SEGMENTS` times the uniform
segments and a mean speed of :data:`ASSUMED_MEAN_SPEED_MPS` (or the vehicle's top speed, if
lower), and adds :data:`SAFETY` (25 %): it lies 1.0 to 1.8 times above the measured peak on
those routes, 2 to 3.5 times on long, smooth, fast ones (where the vehicle keeps its top
speed and the simulation takes a quarter of the steps assumed). Examples (measured peak,
estimate): 40,000 samples at 0.05 m (2 km) 152 MB, 275 MB; 640,000 (32 km) 1.18 GB, 1.59 GB;
2.35 million (117 km, a 39 MB file) 3.16 GB, 5.3 GB; 180,000 samples at 0.5 m of slow rough
ground (90 km, 6 m/s) 1.30 GB, 1.85 GB; ``drive`` (the same plan, the online drive beside it)
peaks 10 to 25 % above ``plan`` (8 km: 396 MB, 16 km: 694 MB), within the estimate. A route
over ``--max-memory`` (default :data:`MAX_MEMORY_GB`, 1.5 GB: about 600,000 samples at 0.05 m,
30 km; 140,000 at 0.5 m, 71 km) is refused with one line naming the estimate, the route's
samples and what would fit.

The fit was measured before the exact simulation computed its forces and rows in chunks
(:mod:`profileopt.physics.simulate`) and before SBEM:TF's (segment, window) pairs were
intersected in blocks (:func:`profileopt.physics.speeds.speed_bands_of_sets`), both
2026-11-28. Measured again after them (``/usr/bin/time -v``, 17 plans: ISO 8608 classes A-E
at 0.05 and 0.5 m, 2 to 90 km, an x,y,z route, the bundled trail and four of it end to end,
both atvs, refined and not), the estimate lies 1.03 to 3.8 times above every peak: 2 to 3.8
times on fast routes (8 km of class C at 0.05 m: 206 MB, estimate 539 MB; 60 km of class A:
0.97 GB, 2.8 GB), and closest on slow rough ones with the resonant atv, whose plans have 14
times the uniform segments and a third of the assumed speed (8 km of class E: 616 MB,
estimate 635 MB; the trail four times: 611 MB, 635 MB; 90 km of class E at 0.5 m: 1.74 GB,
2.9 GB). Before the blocks the class E plan peaked at 1.49 GB, 2.3 times above its estimate.
The same plans fit 79 MB + 0.66 kB x samples + 7.5 kB x segments + 0.23 kB x simulation steps
(within 14 % of every peak but an x,y,z route's, 30 % above it); the estimate keeps the older, larger
coefficients because it cannot know a plan's segments and travel time before planning, and
the slow plans need that room.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ..errors import InputError

if TYPE_CHECKING:
    from ..core.vehicle import Vehicle

__all__ = ["MAX_MEMORY_GB", "PLAN_BASE_BYTES", "PLAN_BYTES_PER_SAMPLE", "PLAN_BYTES_PER_SEGMENT",
           "PLAN_BYTES_PER_STEP", "REFINED_SEGMENTS", "ASSUMED_MEAN_SPEED_MPS", "SAFETY", "MAX_MEMORY_HELP",
           "PlanMemory", "estimated_plan_bytes", "check_plan_memory"]

#: The default of ``--max-memory`` (GB): what the documentation promises a plan of the
#: largest route needs (docs/guide/bad-input.md), and ``verify``'s default.
MAX_MEMORY_GB = 1.5
#: Memory of a plan whatever the route (bytes): the interpreter, NumPy, SciPy, CasADi.
PLAN_BASE_BYTES = 150e6
#: Memory per route sample (bytes): the route, its roughness windows, the wheel's path and
#: the simulation's arrays along it.
PLAN_BYTES_PER_SAMPLE = 1_130
#: Memory per segment of the plan (bytes): the NLP and its solver.
PLAN_BYTES_PER_SEGMENT = 3_600
#: Memory per time step of the planner's exact simulation (bytes).
PLAN_BYTES_PER_STEP = 505
#: Segments a refined plan is assumed to have, per uniform segment (measured: 1 to 10.5
#: times, 4 to 5 on the bundled rough routes).
REFINED_SEGMENTS = 4
#: Mean speed (m/s) the estimate of the simulation's time steps assumes (the travel time is
#: not known before planning): a rough route's (6 m/s measured on classes E and F at 0.5 m
#: spacing, 12 m/s on the bundled trail).
ASSUMED_MEAN_SPEED_MPS = 5.0
#: Share added to the estimate for what the fit misses (a rough route's wheel path).
SAFETY = 0.25
#: ``--max-memory``'s help, shared by plan and drive.
MAX_MEMORY_HELP = (f"refuse, before planning, a route whose plan would need more memory than this, in GB ('inf': no "
                   f"bound; default: {MAX_MEMORY_GB:g}). The estimate: 0.15 GB + 1.13 kB per route sample + "
                   f"3.6 kB per segment ({REFINED_SEGMENTS} per uniform one when refined) + 0.5 kB per time step "
                   f"of the plan's simulation (at {ASSUMED_MEAN_SPEED_MPS:g} m/s), plus {100 * SAFETY:g} %%: "
                   "1.5 GB for about 600,000 samples at 0.05 m (30 km), 140,000 at 0.5 m (71 km)")


class PlanMemory:
    """The estimate of a plan's peak memory and what it is made of.

    Parameters
    ----------
    samples : int
        The route's samples.
    length_m : float
        The route's length (m).
    segment_length_m : float
        The planning resolution (m).
    refine : bool
        Whether the plan refines its segments.
    vehicle : Vehicle
        Its natural frequency sets the simulation's time step, its top speed may cap the
        speed assumed.
    """

    def __init__(self, samples: int, length_m: float, segment_length_m: float, refine: bool,
                 vehicle: "Vehicle") -> None:
        from ..physics.simulate import choose_time_step_s

        self.samples = int(samples)
        self.length_m = float(length_m)
        self.segments = int(math.ceil(self.length_m / segment_length_m)) * (REFINED_SEGMENTS if refine else 1)
        speed = min(ASSUMED_MEAN_SPEED_MPS, float(vehicle.max_speed_mps))
        self.speed_mps = speed
        self.steps = int(math.ceil(self.length_m / (speed * choose_time_step_s(vehicle.natural_frequency_radps))))
        self.per_metre = (PLAN_BYTES_PER_SEGMENT * self.segments + PLAN_BYTES_PER_STEP * self.steps) / max(
            self.length_m, 1e-9)
        self.bytes = estimated_plan_bytes(self.samples, self.segments, self.steps)


def estimated_plan_bytes(samples: int, segments: int, steps: int) -> float:
    """The estimated peak memory of a plan (bytes), with the safety margin.

    Parameters
    ----------
    samples : int
        Route samples.
    segments : int
        Segments of the plan (the refined count, when refined).
    steps : int
        Time steps of the planner's exact simulation.

    Returns
    -------
    float
        (:data:`PLAN_BASE_BYTES` + :data:`PLAN_BYTES_PER_SAMPLE` x samples +
        :data:`PLAN_BYTES_PER_SEGMENT` x segments + :data:`PLAN_BYTES_PER_STEP` x steps)
        x (1 + :data:`SAFETY`).
    """
    return (1.0 + SAFETY) * (PLAN_BASE_BYTES + PLAN_BYTES_PER_SAMPLE * samples + PLAN_BYTES_PER_SEGMENT * segments
                             + PLAN_BYTES_PER_STEP * steps)


def check_plan_memory(source: str, memory: PlanMemory, max_memory_gb: float, *, spacing_m: float | None = None,
                      what: str = "planning it") -> None:
    """Refuse, before planning, a route whose plan would need more than ``max_memory_gb``.

    Parameters
    ----------
    source : str
        The route or track file, for the message.
    memory : PlanMemory
        The estimate.
    max_memory_gb : float
        ``--max-memory`` (GB); inf: no bound.
    spacing_m : float, optional
        For a track: the spacing it is (or would be) sampled at; the message then names the
        coarsest ``--spacing`` that fits, where one does.
    what : str, default "planning it"
        What needs the memory, for the message.

    Raises
    ------
    InputError
        One line: the estimate, the route's samples, segments and steps, the bound, and
        what would fit (a coarser ``--spacing``, the route in parts, or ``--max-memory``).
    """
    if math.isinf(max_memory_gb) or memory.bytes <= max_memory_gb * 1e9:
        return
    room = max_memory_gb * 1e9 / (1.0 + SAFETY) - PLAN_BASE_BYTES  # for what grows with the route
    fixes = []
    if spacing_m is not None:
        left = room - memory.per_metre * memory.length_m - PLAN_BYTES_PER_SAMPLE
        if left > 0:
            coarsest = PLAN_BYTES_PER_SAMPLE * memory.length_m / left
            step = 10.0 ** (math.floor(math.log10(coarsest)) - 1)
            fixes.append(f"give --spacing {math.ceil(coarsest / step * (1 - 1e-12)) * step:.2g} or more")
    variable = memory.bytes / (1.0 + SAFETY) - PLAN_BASE_BYTES
    parts = max(int(math.ceil(variable / room)), 2) if room > 0 else None
    if parts is not None:
        fixes.append(f"split it into {parts} parts of about {memory.length_m / parts / 1000:.3g} km")
    need = math.ceil(memory.bytes / 1e8) / 10
    fixes.append(f"pass --max-memory {need:g} on a machine with more memory")
    raise InputError(
        f"{source}: {what} needs about {memory.bytes / 1e9:.2g} GB of memory ({memory.samples:,} route samples over "
        f"{memory.length_m / 1000:.4g} km, {memory.segments:,} segments, {memory.steps:,} simulation steps at an "
        f"assumed {memory.speed_mps:g} m/s; see profileopt.cli.memory), more than --max-memory {max_memory_gb:g} GB; "
        + (", ".join(fixes[:-1]) + ", or " if len(fixes) > 1 else "") + fixes[-1])
