"""C code for the force limits: the Functions of :mod:`profileopt.mpc.constraints` as C source.

:func:`export_c` writes, into one directory,

* ``<base>.c`` and ``<base>.h``: CasADi-generated C (``casadi.CodeGenerator`` with
  ``with_header``) for each model's force and constraint Functions and their Jacobians,
  with the vehicle's constants folded in as numbers;
* ``example.c``: a small program calling one constraint and its Jacobian;
* ``README.md``: how to call the functions (argument and result pointer arrays, work
  arrays, ``casadi_int``, the ``*_work`` functions), written for the files exported.

With ``intervals=True`` it adds, for each model defined on e_max, the interval rows of
:func:`profileopt.mpc.horizon.interval_force_constraints` (``<slug>_<model>_interval_constraint_of_e_max``:
the limit over every speed between two stages' speeds); with a ``preview``
(:class:`profileopt.mpc.preview.TerrainPreview`), its five envelopes, each of the stage
positions, the horizon's origin and one coefficient vector: the terrain's
``<slug>_preview_e_max`` and ``<slug>_preview_speed_cap``, whose coefficients
:meth:`~profileopt.mpc.preview.TerrainPreview.coefficients` computes each step, and the
path's ``<slug>_preview_curvature``, ``<slug>_preview_grade_max`` and
``<slug>_preview_grade_min``, whose coefficients
:meth:`~profileopt.mpc.preview.TerrainPreview.path_coefficients` computes.

Function names are ``<slug>_<model>_<kind>_of_<terrain>`` with ``kind`` ``force`` (output
``force_n``, N) or ``constraint`` (output ``g`` = F / F_limit - 1, dimensionless, <= 0 when
admissible), ``terrain`` ``ri`` (roughness index) or ``e_max`` (worst-case elevation, m),
and ``<slug>`` the vehicle's name as a C identifier (``atv-resonant`` -> ``atv_resonant``),
so that the code of several vehicles can be linked into one program. Each has a ``_jac``
companion with the same inputs and the outputs ``jac_<output>_speed_mps`` and
``jac_<output>_ri`` / ``jac_<output>_e_max_m`` (the derivatives, diagonal matrices for
several stages).

Every file is written atomically (:mod:`profileopt.io.atomic`): after a failure nothing is left
half-written.
"""

from __future__ import annotations

import dataclasses
import re
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

import casadi as ca

from ..defaults import MAX_C_BYTES
from ..errors import InputError
from ..io.atomic import OutputSet, atomic_write
from ..physics.forces import DEFAULT_MODEL, FORCE_OF_E_MAX, MODELS, get_model
from .constraints import force_limit_n
from .functions import constraint_function, force_function, interval_constraint_function, jacobian_function

if TYPE_CHECKING:
    from ..core.vehicle import Vehicle
    from .preview import TerrainPreview

__all__ = ["ExportedFunction", "CExport", "vehicle_slug", "jacobian_function", "c_functions", "export_c",
           "export_c_paths", "C_BYTES_PER_STAGE", "C_BYTES_PER_INTERVAL", "C_BYTES_PER_PREVIEW_KNOT", "MAX_C_BYTES"]

#: Bytes of C per stage that each model's two Functions and their Jacobians add (measured
#: with CasADi 3.6 at 1 and 1000 stages: the code is unrolled, one block per stage).
C_BYTES_PER_STAGE = {"prev_bem": 1275, "iecm": 4815, "sbem_ef": 6674, "sbem_tf": 10913}
#: Bytes of C per stage of each model's interval rows and their Jacobian (measured with
#: CasADi 3.8 at 1 and 21 stages: 2.5, 3.0 and 18.4 kB; rounded up).
C_BYTES_PER_INTERVAL = {"iecm": 3000, "sbem_ef": 3500, "sbem_tf": 20000}
#: Bytes of C per stage and per knot interval of a preview's five envelopes (e_max, speed
#: cap, curvature, grade_max, grade_min) and their Jacobians (measured with CasADi 3.8.2 at 1
#: and 10 stages, 26 and 46 knot intervals: 6.5-7.6 kB; rounded up).
C_BYTES_PER_PREVIEW_KNOT = 8000


@dataclasses.dataclass(frozen=True)
class ExportedFunction:
    """One exported C function and its Jacobian companion.

    Attributes
    ----------
    name : str
        C name of the value function, e.g. ``"atv_sbem_tf_constraint_of_ri"``.
    jacobian_name : str
        C name of its Jacobian, ``name + "_jac"``.
    model : str
        Force model key.
    kind : str
        ``"force"`` (output ``force_n``, N) or ``"constraint"`` (output ``g``).
    terrain : str
        ``"ri"`` (input ``ri``) or ``"e_max"`` (input ``e_max_m``, m).
    inputs : str
        The inputs, with their units, for the README.
    output : str
        The output, with its unit, for the README.
    """

    name: str
    jacobian_name: str
    model: str
    kind: str
    terrain: str
    inputs: str = ""
    output: str = ""


@dataclasses.dataclass(frozen=True)
class CExport:
    """What :func:`export_c` wrote.

    Attributes
    ----------
    directory : pathlib.Path
    source, header, example, readme : pathlib.Path
        The C source, its header, the example program and the README.
    functions : tuple of ExportedFunction
    n_stages : int
        Length of every input and output vector.
    """

    directory: Path
    source: Path
    header: Path
    example: Path
    readme: Path
    functions: tuple[ExportedFunction, ...]
    n_stages: int


def vehicle_slug(vehicle: "Vehicle") -> str:
    """The vehicle's name as a C identifier: the file stem, non-identifier characters as '_'.

    Parameters
    ----------
    vehicle : Vehicle
        Named by ``vehicle.name`` (its file), ``"vehicle"`` if it has none.
    """
    stem = Path(vehicle.name).stem if vehicle.name else "vehicle"
    # runs of '_' collapsed and none at the ends: CasADi refuses names with '__' in them
    slug = re.sub(r"_+", "_", re.sub(r"[^A-Za-z0-9_]", "_", stem)).strip("_") or "vehicle"
    if slug[0].isdigit():
        slug = "v_" + slug
    return slug


def _check_models(models: Sequence[str] | None) -> list[str]:
    if models is None:
        return list(MODELS)
    out = []
    for m in models:
        get_model(m)
        if m not in out:
            out.append(m)
    if not out:
        raise InputError("no model given; choose one or more of " + ", ".join(MODELS))
    return out


def c_functions(
    vehicle: "Vehicle",
    *,
    models: Sequence[str] | None = None,
    n_stages: int = 1,
    intervals: bool = False,
    preview: "TerrainPreview | None" = None,
) -> list[tuple[ExportedFunction, ca.Function, ca.Function]]:
    """The Functions :func:`export_c` generates, with their C names.

    Parameters
    ----------
    vehicle : Vehicle
    models : sequence of str, optional
        Model keys; default all four.
    n_stages : int, default 1
        Length of the input and output vectors.
    intervals : bool, default False
        Also each model's interval rows (models defined on e_max only).
    preview : TerrainPreview, optional
        Also its five envelopes (built for ``vehicle``): ``e_max`` and ``speed_cap``
        (:meth:`~profileopt.mpc.preview.TerrainPreview.stage_functions`), then ``curvature``,
        ``grade_max`` and ``grade_min``
        (:meth:`~profileopt.mpc.preview.TerrainPreview.path_stage_functions`).

    Returns
    -------
    list of (ExportedFunction, value Function, Jacobian Function)
        For each model: force and constraint against the RI, then (except Prev:BEM) against
        e_max, then its interval rows; then the preview's five envelopes (``model``
        ``"preview"``, ``kind`` the envelope's name, ``terrain`` ``"position"``).
    """
    slug = vehicle_slug(vehicle)
    out = []
    for model in _check_models(models):
        terrains = ["ri", "e_max"] if model in FORCE_OF_E_MAX else ["ri"]
        for terrain in terrains:
            for kind, builder in (("force", force_function), ("constraint", constraint_function)):
                name = f"{slug}_{model}_{kind}_of_{terrain}"
                fn = builder(vehicle, model=model, terrain=terrain, n_stages=n_stages, name=name)
                jac = jacobian_function(fn)
                terrain_in = "`ri` (RI, -)" if terrain == "ri" else "`e_max_m` (e_max, m)"
                output = "`force_n` (N)" if kind == "force" else "`g` = F / F_limit - 1 (-, <= 0 admissible)"
                out.append((ExportedFunction(name, jac.name(), model, kind, terrain, f"`speed_mps` (m/s), {terrain_in}",
                                             output), fn, jac))
        if intervals and model in FORCE_OF_E_MAX:
            name = f"{slug}_{model}_interval_constraint_of_e_max"
            fn = interval_constraint_function(vehicle, model=model, n_stages=n_stages, name=name)
            rows = fn.size1_out(0) // n_stages
            out.append((ExportedFunction(name, f"{name}_jac", model, "interval_constraint", "e_max",
                                         "`v_start`, `v_end` (m/s), `e_max_m`, `e_min_m` (m)",
                                         f"`g`: {rows} rows per interval, F / F_limit - 1 (-, <= 0 admissible)"),
                        fn, jacobian_function(fn)))
    if preview is not None:
        if preview.vehicle != vehicle:
            raise InputError("c_functions: the preview was built for another vehicle; build it with this one")
        e_fn, cap_fn = preview.stage_functions(n_stages=n_stages, prefix=f"{slug}_preview")
        kappa_fn, up_fn, down_fn = preview.path_stage_functions(n_stages=n_stages, prefix=f"{slug}_preview")
        k = preview.n_coefficients
        for fn, kind, coef, output in ((e_fn, "e_max", "e_coef", "`e_max_m` (m)"),
                                       (cap_fn, "speed_cap", "cap_coef", "`speed_cap_mps` (m/s)"),
                                       (kappa_fn, "curvature", "curvature_coef", "`curvature_1pm` (1/m)"),
                                       (up_fn, "grade_max", "grade_max_coef", "`grade_max_rad` (rad)"),
                                       (down_fn, "grade_min", "grade_min_coef", "`grade_min_rad` (rad)")):
            out.append((ExportedFunction(fn.name(), f"{fn.name()}_jac", "preview", kind, "position",
                                         f"`s_m` (m), `origin_m` (m, 1 value), `{coef}` ({k} values)", output),
                        fn, jacobian_function(fn)))
    return out


def export_c(
    vehicle: "Vehicle",
    directory: str | Path,
    *,
    models: Sequence[str] | None = None,
    n_stages: int = 1,
    basename: str | None = None,
    intervals: bool = False,
    preview: "TerrainPreview | None" = None,
) -> CExport:
    """Write C source, header, example program and README for the force limits.

    Parameters
    ----------
    vehicle : Vehicle
        Its constants are folded into the code.
    directory : str or pathlib.Path
        Output folder; created if missing.
    models : sequence of str, optional
        Model keys; default all four.
    n_stages : int, default 1
        Length of every input and output vector (one horizon at once).
    basename : str, optional
        Base of the file names (a C identifier); default ``profileopt_<slug>``.
    intervals : bool, default False
        Also the interval rows of each model defined on e_max (:func:`c_functions`).
    preview : TerrainPreview, optional
        Also the preview's five envelopes (terrain and path), for stage positions
        (:func:`c_functions`).

    Returns
    -------
    CExport

    Raises
    ------
    InputError
        Unknown model, ``directory`` is a file, a bad ``basename`` or ``n_stages``, or files
        estimated above :data:`MAX_C_BYTES` (said before any work, with their size).
    """
    if not (isinstance(n_stages, int) and not isinstance(n_stages, bool) and n_stages >= 1):
        raise InputError(f"n_stages = {n_stages!r}: must be an integer >= 1")
    _check_size(models, n_stages, intervals, preview)
    paths = export_c_paths(vehicle, directory, basename=basename)
    base = paths[0].stem
    directory = Path(directory)
    triples = c_functions(vehicle, models=models, n_stages=n_stages, intervals=intervals, preview=preview)

    cg = ca.CodeGenerator(f"{base}.c", {"with_header": True})
    for _, fn, jac in triples:
        cg.add(fn)
        cg.add(jac)
    with tempfile.TemporaryDirectory() as tmp:
        cg.generate(str(Path(tmp)) + "/")
        source_text = _mark_unused_parameters((Path(tmp) / f"{base}.c").read_text(encoding="utf-8"))
        header_text = (Path(tmp) / f"{base}.h").read_text(encoding="utf-8")

    exported = tuple(t[0] for t in triples)
    example_fn = next(e for e in exported if e.kind == "constraint" and e.model == _example_model(exported)
                      and e.terrain == "ri")
    files = {
        f"{base}.c": source_text,
        f"{base}.h": header_text,
        "example.c": _example_c(base, example_fn, n_stages),
        "README.md": _readme(vehicle, base, exported, example_fn, n_stages),
    }
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"directory {directory}: cannot create the folder ({exc.strerror}); choose another path") from None
    with OutputSet([("", directory / file_name) for file_name in files]):  # all four or none
        for file_name, text in files.items():
            with atomic_write(directory / file_name) as handle:
                handle.write(text)
    return CExport(
        directory=directory,
        source=directory / f"{base}.c",
        header=directory / f"{base}.h",
        example=directory / "example.c",
        readme=directory / "README.md",
        functions=exported,
        n_stages=n_stages,
    )


#: A function definition as CasADi writes it: on one line at column 0, ending with "{".
_DEFINITION = re.compile(r"^(?![#/ \t])[^;()]*\b\w+\((?P<params>[^()]*)\)\s*\{\s*$")


def _mark_unused_parameters(source: str) -> str:
    """``source`` with ``(void)name;`` for each parameter a function body does not use.

    CasADi gives every generated function the full signature ``(arg, res, iw, w, mem)``
    whether or not the body needs the work arrays, and has no option to mark the unused
    ones (casadi/casadi#1741, #1875), so ``-Wextra`` warns about each (112 warnings for the
    default export). The casts go just before the body's last ``return`` (or its closing
    brace), after every declaration, so the code stays valid C89 as well.
    """
    lines = source.split("\n")
    out: list[str] = []
    i = 0
    while i < len(lines):
        match = _DEFINITION.match(lines[i])
        if not match:
            out.append(lines[i])
            i += 1
            continue
        end = i + 1
        while end < len(lines) and lines[end] != "}":
            end += 1
        if end == len(lines):  # not a body CasADi writes: leave it alone
            out.append(lines[i])
            i += 1
            continue
        body = lines[i + 1:end]
        names = []
        for param in match.group("params").split(","):
            words = re.findall(r"\w+", param)
            if words and words != ["void"] and not re.search(rf"\b{words[-1]}\b", "\n".join(body)):
                names.append(words[-1])
        at = len(body) - 1 if body and re.match(r"^  return\b", body[-1]) else len(body)
        casts = [f"  (void){name};" for name in names]
        out.extend([lines[i], *body[:at], *casts, *body[at:], lines[end]])
        i = end + 1
    return "\n".join(out)


def export_c_paths(vehicle: "Vehicle", directory: str | Path, *, basename: str | None = None) -> list[Path]:
    """The four files :func:`export_c` writes: source, header, example program, README.

    Parameters
    ----------
    vehicle : Vehicle
        Names the files (``profileopt_<slug>``, see :func:`vehicle_slug`).
    directory : str or pathlib.Path
        The output folder (it need not exist yet).
    basename : str, optional
        Base of the file names (a C identifier); default ``profileopt_<slug>``.

    Returns
    -------
    list of pathlib.Path

    Raises
    ------
    InputError
        ``directory`` is empty or exists and is not a folder, or ``basename`` is not a C
        identifier.
    """
    base = basename or f"profileopt_{vehicle_slug(vehicle)}"
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", base):
        raise InputError(f"file base name {base!r} is not a C identifier; use letters, digits and '_'")
    if not str(directory):
        raise InputError("directory '': the output folder is empty; give the path of a folder for the C files")
    directory = Path(directory)
    if directory.exists() and not directory.is_dir():
        raise InputError(f"{directory}: exists and is not a folder; choose a folder for the C files")
    return [directory / f"{base}.c", directory / f"{base}.h", directory / "example.c", directory / "README.md"]


def _check_size(models: Sequence[str] | None, n_stages: int, intervals: bool = False,
                preview: "TerrainPreview | None" = None) -> None:
    """Refuse, before any work, an export estimated above :data:`MAX_C_BYTES`."""
    keys = [m for m in (list(models) if models else list(MODELS)) if m in C_BYTES_PER_STAGE]
    per_stage = sum(C_BYTES_PER_STAGE[m] for m in dict.fromkeys(keys))
    if intervals:
        per_stage += sum(C_BYTES_PER_INTERVAL.get(m, 0) for m in dict.fromkeys(keys))
    if preview is not None:
        per_stage += C_BYTES_PER_PREVIEW_KNOT * preview.n_intervals
    if per_stage and per_stage * n_stages > MAX_C_BYTES:
        raise InputError(
            f"n_stages = {n_stages}: the C files would be about {per_stage * n_stages / 1e6:,.0f} MB "
            f"({per_stage / 1e3:.1f} kB per stage for {len(set(keys))} model(s)), above the "
            f"{MAX_C_BYTES / 1e6:.0f} MB written at most; use at most {MAX_C_BYTES // per_stage} stages and "
            "evaluate a longer horizon in pieces")


def _example_model(exported: Sequence[ExportedFunction]) -> str:
    models = [e.model for e in exported]
    return DEFAULT_MODEL if DEFAULT_MODEL in models else models[0]


def _example_c(base: str, fn: ExportedFunction, n_stages: int) -> str:
    jac = fn.jacobian_name
    n = n_stages
    ri = ", ".join(f"{0.05 + 0.05 * i:.2f}" for i in range(n))
    speed = ", ".join(f"{5.0 + i:.1f}" for i in range(n))
    return f"""\
/* Evaluate the force constraint g = F / F_limit - 1 (<= 0: admissible) and its Jacobian.
   Build: cc -O2 example.c {base}.c -lm -o example && ./example */
#include <stdio.h>
#include "{base}.h"

int main(void) {{
  casadi_real speed_mps[{n}] = {{{speed}}};  /* m/s */
  casadi_real ri[{n}] = {{{ri}}};  /* roughness index, dimensionless */
  casadi_real g[{n}], dg_dspeed[{n}], dg_dri[{n}];  /* Jacobians are diagonal: n values */
  const casadi_real* arg[{jac}_SZ_ARG] = {{speed_mps, ri}};
  casadi_real* res[{jac}_SZ_RES] = {{dg_dspeed, dg_dri}};
  casadi_int iw[{jac}_SZ_IW + 1];  /* + 1: C has no zero-length arrays */
  casadi_real w[{jac}_SZ_W + 1];
  int i;
  if ({jac}(arg, res, iw, w, 0)) return 1;
  {{
    const casadi_real* arg_g[{fn.name}_SZ_ARG] = {{speed_mps, ri}};
    casadi_real* res_g[{fn.name}_SZ_RES] = {{g}};
    casadi_int iw_g[{fn.name}_SZ_IW + 1];
    casadi_real w_g[{fn.name}_SZ_W + 1];
    if ({fn.name}(arg_g, res_g, iw_g, w_g, 0)) return 1;
  }}
  for (i = 0; i < {n}; ++i)
    printf("speed %.17g m/s, RI %.17g: g %.17g, dg/dspeed %.17g s/m, dg/dRI %.17g\\n",
           speed_mps[i], ri[i], g[i], dg_dspeed[i], dg_dri[i]);
  return 0;
}}
"""


def _extras(exported: Sequence[ExportedFunction]) -> str:
    """The README's paragraphs on the interval rows and the preview, when exported."""
    text = ""
    if any(e.kind == "interval_constraint" for e in exported):
        text += """
The `*_interval_constraint_of_e_max` functions hold the force limit at every speed between
two consecutive stages' speeds `v_start`, `v_end` (constant acceleration between them), for
every elevation in [`e_min_m`, `e_max_m`] (give `e_min_m` 0 for "any terrain up to e_max"):
2 rows per interval (3 for SBEM:TF with a resonance peak), interval by interval, each
<= 0 when admissible. Use them in place of the point constraints between grid points
(Python: `profileopt.mpc.horizon.interval_force_constraints`, the MPC guide).
"""
    if any(e.model == "preview" for e in exported):
        text += """
The `*_preview_*` functions are a `TerrainPreview`'s envelopes (Python:
`profileopt.mpc.preview.TerrainPreview`, built with the same horizon, reach, knot spacing
and unseen assumption), each at every stage position `s_m`, given the horizon's origin
`origin_m` and one coefficient vector:

* `*_preview_e_max` (m) and `*_preview_speed_cap` (m/s), the terrain's: coefficients from
  `TerrainPreview.coefficients` over the terrain measured so far (its `origin_m`, `e_max`
  and `speed_cap`);
* `*_preview_curvature` (|curvature|, 1/m), `*_preview_grade_max` and `*_preview_grade_min`
  (steepest and least grade, rad), the path's: coefficients from
  `TerrainPreview.path_coefficients` (its `origin_m`, `curvature`, `grade_max` and
  `grade_min`), for the lateral and friction limits (`lateral_constraints` at `v_k` and
  `v_k+1` with the curvature at `s_k`; `friction_constraints` at both grades).

The coefficients are parameters: compute them each step (in Python, or port those
functions) and pass them in; the code does not change with the terrain or the path. Each
envelope holds only for a stage at most the preview's reach long: keep
0 <= s_k+1 - s_k <= reach in your problem (Python: `reach_constraints`) and check the
solved positions (`check_stage_lengths`).
"""
    return text


def _readme(vehicle: "Vehicle", base: str, exported: Sequence[ExportedFunction], example_fn: ExportedFunction, n_stages: int) -> str:
    rows = []
    for e in exported:
        label = "the preview" if e.model == "preview" else get_model(e.model).label
        rows.append(f"| `{e.name}` / `{e.jacobian_name}` | {label} | {e.inputs} | {e.output} |")
    limits = ", ".join(
        f"{get_model(m).label} {force_limit_n(vehicle, model=m):g} N"
        for m in dict.fromkeys(e.model for e in exported if e.model != "preview")
    )
    stages = (
        "one stage: every input and output is a single number"
        if n_stages == 1
        else f"{n_stages} stages: every input and output is a vector of {n_stages} numbers "
        "(elementwise); each Jacobian is diagonal and stored as its "
        f"{n_stages} diagonal entries (sparse, see `*_sparsity_out`)"
    )
    fn, jac = example_fn.name, example_fn.jacobian_name
    speeds = ", ".join(["8.0"] * n_stages)
    ris = ", ".join(["0.2"] * n_stages)
    return f"""\
# Force limits of vehicle `{vehicle_slug(vehicle)}` in C

Generated by `profileopt export-c` from `{Path(vehicle.name).name or vehicle_slug(vehicle)}` with CasADi {ca.__version__}.
The vehicle's constants are folded into the code as numbers; re-export after changing the
vehicle file. Force limits: {limits}. Exported with {stages}.

Files: `{base}.c` (source), `{base}.h` (header), `example.c` (a small program).

## Functions

| value / Jacobian | model | inputs | output |
|---|---|---|---|
{chr(10).join(rows)}

Each `_jac` function takes the same inputs and returns one block per input, in the order of
the inputs (`jac_<output>_<input>`): for the forces and constraints `jac_<output>_speed_mps`
(per m/s) then `jac_<output>_ri` or `jac_<output>_e_max_m` (per m). On smooth ground
(terrain value 0) the force is 0. Speeds are in m/s, e_max in m, forces in N; RI and g are
dimensionless.
{_extras(exported)}
A negative or NaN terrain value (RI or e_max) is not terrain: every function returns NaN
there (a force of NaN, g = NaN), never a g <= 0, so a check `g <= 0` (false for NaN)
rejects it. Keep it so: do not compile with `-ffast-math` or `-ffinite-math-only`, which
let the compiler assume that no NaN occurs.

## Calling convention

Every function has the CasADi signature

```c
int NAME(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem);
```

* `arg`: an array of `NAME_SZ_ARG` pointers, one per input in the order of the table
  (`arg[0]` speeds, `arg[1]` terrain values). A null pointer means "all zeros".
* `res`: an array of `NAME_SZ_RES` pointers, one per output; a null pointer skips that
  output.
* `iw`, `w`: integer and real work arrays of at least `NAME_SZ_IW` and `NAME_SZ_W`
  elements (give one more element: C has no zero-length arrays). `NAME_work(&sz_arg,
  &sz_res, &sz_iw, &sz_w)` returns the same sizes at run time (element counts) and
  `NAME_work_bytes` the sizes in bytes, for allocating them dynamically.
* `mem`: pass 0. These functions keep no state (`NAME_checkout`/`NAME_release` exist
  for the generic CasADi interface).
* Returns 0 on success.
* `casadi_real` is `double` and `casadi_int` is `long long int` unless you define them
  before including the header; define them the same way when compiling `{base}.c`
  (e.g. `-Dcasadi_int=int`). `{base}_casadi_int_size()` and `{base}_casadi_real_size()`
  report what the library was compiled with.
* Internal symbols are prefixed with `{base}_`, so code exported for several vehicles can be
  linked into one program.

## Example

```c
#include "{base}.h"

casadi_real speed_mps[{n_stages}] = {{{speeds}}}, ri[{n_stages}] = {{{ris}}}, g[{n_stages}];
const casadi_real* arg[{fn}_SZ_ARG] = {{speed_mps, ri}};  /* m/s, dimensionless */
casadi_real* res[{fn}_SZ_RES] = {{g}};
casadi_int iw[{fn}_SZ_IW + 1];
casadi_real w[{fn}_SZ_W + 1];
{fn}(arg, res, iw, w, 0);  /* g <= 0: the force is within its limit */
```

`example.c` does this for every stage, with the Jacobian `{jac}`. Build and run it:

```sh
cc -O2 example.c {base}.c -lm -o example && ./example
```

A shared library for CasADi's `external` (Python: `casadi.external("{fn}", "./lib{base}.so")`):

```sh
cc -shared -fPIC -O2 {base}.c -lm -o lib{base}.so
```
"""
