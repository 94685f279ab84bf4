#!/usr/bin/python3
"""Contact benchmark of internodes against one dolfinx elastic solve: ``make bench`` (second part).

Problem: the 3D hemisphere-on-block contact of ``geo/hemisphere_on_block.toml``
(sphere R = 1 pushed down by delta = 0.01 at its flat top, block base clamped,
E = 1000, nu = 0.3, frictionless, contact radius a ~ 0.1 R), meshed with the
case's geo parameters (h_c = R/67 in the contact zone r < 0.16, h_far = R/2)
at five refinement levels of ``geo/hemisphere_on_block.geo`` (every mesh size
times 2^-level): about 31k, 99k, 217k, 1.02M and 3.06M DOFs (both bodies). The contact
zone stays resolved at every size (h_c = R/80 .. R/394). The 3M size runs only when
asked (``--sizes 3M`` or ``--sizes full``): gmsh alone takes about 4.5 minutes there.

Our two paths (``internodes solve``), each with its own case file:

  direct     ``[solver] body = "cholesky"``, ``[contact] solver = "schur"``: a sparse
             Cholesky factor of each body; the interface (Schur complement) matrix
             formed densely from the responses to the multipliers (one solve per body
             per active primary node, cached across iterations and load steps).
  iterative  ``[solver] body = "cg-amg"``, ``[contact] solver = "krylov"``: PETSc
             GAMG for each body. Nested solve (older binaries): the interface equation
             by GMRES (half-space preconditioner), each product one CG solve per body.
             Coupled solve: one right-preconditioned GMRES on the whole coupled system
             per active-set iteration, preconditioned by blocks (one AMG V-cycle per
             body, or one Cholesky solve per body on small problems, and a half-space
             approximation of the interface Schur complement).
  default    ``auto`` for both: what the binary picks.

For every size, each of these runs is a separate process, run one after the
other, so that its wall time and peak resident memory (``ru_maxrss`` from
``os.wait4``, through ``benchmark.measure``) are its own:

  1. direct, one step       the full displacement in one step (``load_steps = [1.0]``);
  2. direct, load steps     ``load_steps = [0.5, 1.0]``: half, then the full displacement;
                            the second step starts from the first step's active set and
                            reuses the set-up (factors / AMG hierarchies, operators; the
                            direct path also its cached responses);
  3. iterative, one step    as 1;
  4. iterative, load steps  as 2;
     For 1-4 (and the default path's two runs), the per-iteration times (and, iterative,
     the GMRES iterations: the log's ``interface GMRES: K iterations (+R residuals) ...``
     or ``coupled GMRES: ...`` line before each iteration; and ``summary.json``'s
     ``contact.linear_solvers.body_applications``, each body's block applications over
     the whole solve, where the binary writes it)
     of every step are read from the run's log (``summary.json`` keeps the last step's
     only), the phases from ``summary.json``.
  5. dolfinx, CG + GAMG     ONE linear elastic solve of the same two-body mesh:
  6. dolfinx, MUMPS         both volumes in one dolfinx mesh, the same Dirichlet
                            data (sphere_top displaced by (0, 0, -delta), block_base
                            clamped) and no contact coupling. The bodies are then
                            independent, each held by its own Dirichlet data, so the
                            matrix is SPD. CG + GAMG (rtol 1e-10, rigid-body near-null
                            space) or MUMPS Cholesky, as in ``benchmark.py``; the faster
                            (assembly + setup + solve) is dolfinx's best.
  7. dolfinx, CG + GAMG     the same as 5 under ``mpirun -n 2`` (dolfinx_parallel_elastic.py:
     on 2 MPI ranks         the mesh read by rank 0 and distributed by dolfinx, each phase
                            ended by a barrier and timed on rank 0, peak memory and CPU time
                            summed over the ranks).

The direct path is not run at a size where its Cholesky factors would not fit in
MAX_RSS_GB: the estimate grows the measured Cholesky peak of the largest run of
``validation/BODY_SOLVER_BENCHMARK.md`` (15,094 MB for one body of 676,719 DOFs) like
n^(4/3) (a 3D factor's fill), the DOFs split evenly between the two bodies (the
split that minimizes it): about 20 GB at 1.02M DOFs, where only the iterative path
runs. A run that exceeds a limit anyway is killed and reported as skipped (MUMPS
at 1.02M DOFs probably is: dolfinx's best is then CG + GAMG).

Aims, per path (each figure shown at every size, judged where said):
  1. the whole contact solve (set-up, every active-set iteration, post-processing of the
     one-step run) within twice ONE serial dolfinx CG + GAMG elastic solve (assembly +
     set-up + solve), judged at 99k, 217k, 1M and 3M DOFs; the ratio to the same solve
     on 2 MPI ranks is shown next to it (no aim);
  2. peak memory (the larger of the path's two runs) within 1.5x the serial CG run's,
     judged at 1M and 3M DOFs;
  3. body applications (V-cycles on cg-amg bodies) of each body over the whole one-step
     solve within 4x dolfinx's CG iterations ("n/a" with a binary that does not write
     them);
  4. at most 8 active-set iterations in every load step (both runs);
  5. each extra load step at most 0.25 of the first, the set-up counted in the first:
     step 2 / (set-up + step 1) of the load-stepped run;
  6. on MPI ranks (paths mpi2 and mpi4: the default case file under ``mpirun -n 2`` and ``-n 4``),
     the one-step run's largest rank peak at most 0.6 of the serial (default path) run's peak on
     2 ranks and 0.35 on 4, and its wall time on 2 ranks at most 0.6 of the serial run's, judged
     at 1M and 3M DOFs (4 ranks on fewer cores are oversubscribed: their time is not judged).

Results: a table on stdout, the report ``validation/CONTACT_BENCHMARK.md`` and
the raw numbers ``validation/build/contact_bench/results.json``.

Usage:  /usr/bin/python3 validation/contact_benchmark.py [--sizes small|all|full|NAME[,NAME...]]
                                                        [--paths direct,iterative] [--binary PATH]
        /usr/bin/python3 validation/contact_benchmark.py --report-only

``--sizes small`` is the 31k mesh only, ``all`` the four up to 1M, ``full`` those and 3M,
or names: ``--sizes 1M``, ``--sizes 31k,99k``, ``--sizes 3M --merge`` (3M added to the
sizes of the last results.json). ``--paths`` runs one path only (the other is reported as not run).
The exit status is 1 if one of our runs failed, stopped at a limit or did not converge,
or no dolfinx run finished at a size (a path not run is not a failure).

Run it with nothing else running on the machine: timings are wall times.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import time
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

VALIDATION = Path(__file__).resolve().parent

from benchmark import (CG_RTOL, SERIAL_ENV, RunFailed, environment, fmt,  # noqa: E402
                       markdown, measure, mesh_nodes)

REPO = VALIDATION.parent
BENCH = VALIDATION / "build" / "contact_bench"
REPORT = VALIDATION / "CONTACT_BENCHMARK.md"
BODY_SOLVER_REPORT = VALIDATION / "BODY_SOLVER_BENCHMARK.md"
BASE_CASE = REPO / "geo" / "hemisphere_on_block.toml"
GEO = REPO / "geo" / "hemisphere_on_block.geo"
COMMAND = "make bench   # second command: /usr/bin/python3 validation/contact_benchmark.py --sizes all"
# The 3M size runs only when asked: --sizes full (all five) or --sizes 3M (with --merge to keep the others).
# Our two runs per path and size: the full imposed displacement in one step, and in two load steps.
ONE_STEP = (1.0,)
LOAD_STEPS = (0.5, 1.0)

# path -> the case file's [solver] body and [contact] solver, and a description.
PATHS = {
    "direct": {"body": "cholesky", "solver": "schur",
               "label": "Cholesky factor of each body, dense Schur complement from the responses"},
    "iterative": {"body": "cg-amg", "solver": "krylov",
                  "label": "AMG for each body (PETSc GAMG), the coupled system by GMRES (one V-cycle per body "
                           "per iteration; older binaries: the interface equation by GMRES, CG solves per product)"},
    "default": {"body": "auto", "solver": "auto",
                "label": "what `auto` picks: the coupled GMRES, Cholesky bodies below 30,000 DOFs in the larger "
                         "body and AMG above (older binaries: below 250,000 DOFs)"},
    "mpi2": {"body": "auto", "solver": "auto", "ranks": 2,
             "label": "the default case file under `mpirun -n 2`: each body's rows split between the two ranks "
                      "(METIS), AMG for every body whatever its size, the coupled GMRES on every rank; peak "
                      "memory is the sum of the ranks' peaks (summary.json's rank_peak_memory_mb)"},
    "mpi4": {"body": "auto", "solver": "auto", "ranks": 4,
             "label": "the same under `mpirun -n 4` (oversubscribed where the machine has fewer cores: its "
                      "memory per rank counts, not its time)"},
}

# A run is killed (and reported as skipped) beyond these limits. An iterative run at 1M DOFs
# may take 30 to 60 minutes.
MAX_RSS_GB = 18.0
MAX_SECONDS_OURS = {"direct": 1200.0, "iterative": 5400.0, "default": 5400.0, "mpi2": 5400.0, "mpi4": 5400.0}
MAX_SECONDS_DOLFINX = 600.0
# ... but at the on-request sizes (3M DOFs), where reading and distributing the mesh alone takes minutes.
MAX_SECONDS_DOLFINX_LARGE = 1800.0
# dolfinx's CG + GAMG is also run on this many MPI ranks (mpirun -n MPI_RANKS): a column, no aim.
MPI_RANKS = 2
MPIRUN = "/usr/bin/mpirun"
# Open MPI refuses to run as root without these (harmless otherwise).
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}

# The aims of the module doc (numbered as there).
AIM_TOTAL = 2.0  # 1. one-step contact total / one serial dolfinx CG + GAMG elastic solve, ...
AIM_TOTAL_MIN_DOFS = 90_000  # ... judged at this size and above (99k, 217k, 1M, 3M)
AIM_MEMORY = 1.5  # 2. our peak memory / the serial dolfinx CG + GAMG run's, ...
AIM_MEMORY_MIN_DOFS = 1_000_000  # ... judged at this size and above (1M, 3M)
AIM_APPLICATIONS = 4.0  # 3. body applications (V-cycles) per body over the whole solve / dolfinx's CG iterations
AIM_ITERATIONS = 8  # 4. active-set iterations per load step
AIM_STEP = 0.25  # 5. extra load step / (set-up + first load step)
# 6. Ranks against one process (one-step runs, judged at >= AIM_MEMORY_MIN_DOFS): the largest rank's
# peak / the serial (default path) run's peak, per number of ranks; and the wall time on 2 ranks / the
# serial run's (4 ranks on a 2-core machine are oversubscribed: their time is shown, not judged).
AIM_RANK_PEAK = {2: 0.6, 4: 0.35}
AIM_RANK_WALL = {2: 0.6}
RANK_PATHS = ("mpi2", "mpi4")  # the paths on several ranks, each against "default"

# The largest Cholesky run of BODY_SOLVER_BENCHMARK.md (block_3d, one body, report of 2026-11-26 at
# commit 5096dde): used if that report's table cannot be read. The direct path's estimate starts from it.
CHOLESKY_MEASURED = {"dofs": 676_719, "setup": 191.0, "peak_mb": 15_094.0}


@dataclass(frozen=True)
class Size:
    """One mesh: ``level`` of hemisphere_on_block.geo with the case's geo parameters; ``on_request``:
    run only when named (``--sizes 3M`` or ``--sizes full``), not by ``--sizes all``."""

    name: str
    level: float
    on_request: bool = False

    @property
    def mesh(self) -> Path:
        return BENCH / f"hemisphere_on_block_level{self.level}.msh"

    @property
    def folder(self) -> Path:
        return BENCH / self.name


# With gmsh 4.8: 31 113, 98 700, 216 537 and 1 018 125 DOFs (sphere + block). 2.02 is the smallest
# level (in steps of 0.01) with >= 1M DOFs: level 2.01 gives 997 473, level 2.0 977 565.
# 3M: the DOFs grow like the cube of the refinement 2^level, 2.02 + log2(3) / 3 = 2.55; level 2.56 gives
# 3 059 076 DOFs (1 019 692 nodes; gmsh 4.8, about 4.5 minutes).
SIZES = (Size("31k", 0.25), Size("99k", 0.85), Size("217k", 1.25), Size("1M", 2.02),
         Size("3M", 2.56, on_request=True))

# name -> (label, path, load steps); dolfinx runs have neither.
RUNS = {
    "direct_one": ("direct, one step (1.0)", "direct", ONE_STEP),
    "direct_steps": ("direct, load steps (0.5, 1.0)", "direct", LOAD_STEPS),
    "iterative_one": ("iterative, one step (1.0)", "iterative", ONE_STEP),
    "iterative_steps": ("iterative, load steps (0.5, 1.0)", "iterative", LOAD_STEPS),
    "default_one": ("default, one step (1.0)", "default", ONE_STEP),
    "default_steps": ("default, load steps (0.5, 1.0)", "default", LOAD_STEPS),
    "mpi2_one": ("mpi2, one step (1.0)", "mpi2", ONE_STEP),
    "mpi2_steps": ("mpi2, load steps (0.5, 1.0)", "mpi2", LOAD_STEPS),
    "mpi4_one": ("mpi4, one step (1.0)", "mpi4", ONE_STEP),
    "mpi4_steps": ("mpi4, load steps (0.5, 1.0)", "mpi4", LOAD_STEPS),
    "dolfinx_cg": ("dolfinx, CG + GAMG", None, None),
    "dolfinx_mumps": ("dolfinx, MUMPS Cholesky", None, None),
    "dolfinx_cg_mpi": (f"dolfinx, CG + GAMG, {MPI_RANKS} MPI ranks", None, None),
}
DOLFINX = [run for run, (_, path, _) in RUNS.items() if not path]
OURS = [run for run, (_, path, _) in RUNS.items() if path]


def status(run: dict) -> str:
    """"ok", "not run", "skipped" (stopped at a limit), "failed", or the contact status when not converged."""
    if "not_run" in run:
        return "not run"
    if "error" in run:
        return "skipped" if "stopped after" in run["error"] else "failed"
    return "ok" if run.get("contact_status", "converged") == "converged" else run["contact_status"]


def timed(run: dict) -> bool:
    """Whether the run finished (converged or not) and has timings."""
    return "error" not in run and "not_run" not in run


# ---------------------------------------------------------------------------
# Step 1: meshes, case files, which runs fit
# ---------------------------------------------------------------------------


def base_case() -> tuple[str, dict]:
    """The text of geo/hemisphere_on_block.toml and its parsed contents."""
    text = BASE_CASE.read_text()
    return text, tomllib.loads(text)


def generate_mesh(size: Size) -> None:
    """gmsh -3 hemisphere_on_block.geo with the case's geo_parameters and this level (kept if it exists)."""
    if size.mesh.is_file():
        return
    size.mesh.parent.mkdir(parents=True, exist_ok=True)
    parameters = dict(base_case()[1].get("geo_parameters", {}), level=size.level)
    setnumbers = [arg for name, value in parameters.items() for arg in ("-setnumber", name, str(value))]
    result = subprocess.run(["gmsh", "-3", str(GEO), *setnumbers, "-format", "msh41", "-o", str(size.mesh),
                             "-v", "1"], capture_output=True, text=True)
    if result.returncode != 0:
        raise RunFailed(f"gmsh level {size.level}: {result.stdout[-500:]}{result.stderr[-500:]}")


def write_case(size: Size, run: str, steps: tuple[float, ...], path: str | None) -> Path:
    """The case file of one run: geo/hemisphere_on_block.toml with ``mesh`` pointing at the .msh,
    no ``geo_parameters``, ``load_steps = steps`` instead of its own in its ``[contact]`` table and, for one of
    our paths, its ``[solver] body`` and ``[contact] solver``."""
    size.folder.mkdir(parents=True, exist_ok=True)
    text, data = base_case()
    for table, key in (("contact", "solver"), ("solver", "body")):
        if key in data.get(table, {}):
            raise RunFailed(f"{BASE_CASE}: already has [{table}] {key}; the benchmark sets its own")
    # The demo's load steps give way to the run's own.
    text = re.sub(r"(?m)^load_steps\s*=.*\n", "", text)
    contact = f"[contact]\nload_steps = {list(steps)}"
    if path:
        contact = (f"[solver]\nbody = {json.dumps(PATHS[path]['body'])}\n\n"
                   f"{contact}\nsolver = {json.dumps(PATHS[path]['solver'])}")
    replacements = [(r"(?m)^mesh\s*=.*$", f"mesh = {json.dumps(str(size.mesh))}"),
                    (r"(?m)^geo_parameters\s*=.*\n", ""),
                    (r"(?m)^\[contact\]\s*$", contact)]
    for pattern, replacement in replacements:
        text, count = re.subn(pattern, replacement, text)
        if count != 1:
            raise RunFailed(f"{BASE_CASE}: expected one match of {pattern!r}, found {count}")
    case = size.folder / f"hemisphere_on_block_{run}.toml"
    case.write_text(text)
    return case


def cholesky_measured() -> dict:
    """The largest Cholesky run of validation/BODY_SOLVER_BENCHMARK.md: its DOFs, factorization seconds
    and peak MB (CHOLESKY_MEASURED if the report's table cannot be read)."""
    try:
        lines = BODY_SOLVER_REPORT.read_text().splitlines()
        start = next(i for i, line in enumerate(lines) if line.startswith("|") and "Chol. MB" in line)
        header = [cell.strip() for cell in lines[start].strip().strip("|").split("|")]
        rows = []
        for line in lines[start + 2:]:
            cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
            if not line.startswith("|") or len(cells) != len(header):
                break
            rows.append(dict(zip(header, cells)))
        row = max(rows, key=lambda r: int(r["DOFs"].replace(",", "")))
        return {"dofs": int(row["DOFs"].replace(",", "")), "setup": float(row["Chol. setup"]),
                "peak_mb": float(row["Chol. MB"])}
    except (OSError, StopIteration, KeyError, ValueError):
        return dict(CHOLESKY_MEASURED)


def direct_memory_gb(count: int, measured: dict) -> float:
    """Estimated peak of the direct path's two Cholesky factors: the measured one-body peak grown like
    n^(4/3) (nested-dissection fill in 3D), the DOFs split evenly between the bodies (the least sum)."""
    return measured["peak_mb"] / 1024 * 2 * (count / 2 / measured["dofs"]) ** (4 / 3)


def not_run_reason(path: str, count: int) -> str | None:
    """Why a path is not run at a mesh of ``count`` DOFs (None: it is run)."""
    if path != "direct":
        return None
    measured = cholesky_measured()
    estimate = direct_memory_gb(count, measured)
    if estimate <= MAX_RSS_GB:
        return None
    return (f"the Cholesky factors of both bodies do not fit in {MAX_RSS_GB:g} GB: "
            f"{BODY_SOLVER_REPORT.relative_to(REPO)} measured a {measured['peak_mb']:,.0f} MB peak "
            f"({measured['setup']:.0f} s factorization) for the Cholesky of ONE body of {measured['dofs']:,} DOFs; "
            f"grown like n^(4/3) (a 3D factor's fill) to this mesh's {count:,} DOFs split evenly between the two "
            f"bodies (the most favourable split), that is {estimate:.1f} GB before the responses to the "
            "multipliers")


# ---------------------------------------------------------------------------
# Step 2: the runs
# ---------------------------------------------------------------------------

LOAD_STEP_LINE = re.compile(r"^load step (\d+)/(\d+): factor (\S+)$")
# (Trailing "; paired again" or "; slipping ..." after the seconds and phases.)
ITERATION_LINE = re.compile(r"^\s+iteration\s+(\d+): active\s+(\d+), \+(\d+)\s+-(\d+)\s.*?; ([-+0-9.eE]+) s"
                            r"(?: \(([^)]*)\))?(?:; .*)?\s*$")
# "  Cholesky of the 2 bodies: 0.290 s" ("of both bodies" before several pairs): the body solvers' set-up (the factors, or PETSc + the AMG
# hierarchies on the iterative path, whatever the label says).
BODY_SETUP_LINE = re.compile(r"^\s+(\S.*?) of (?:both|the \d+) bodies: ([-+0-9.eE]+) s$")
# An active-set iteration may print two: a loose solve, then the exact one (summed).
# "interface GMRES" (nested: each product full elastic solves of both bodies) or, since the coupled solve,
# "coupled GMRES" (one right-preconditioned GMRES on the whole coupled system per active-set iteration).
KRYLOV_LINE = re.compile(r"^\s+(interface|coupled) GMRES: (\d+) iterations \(\+(\d+) residuals\), "
                         r"relative residual (\S+) \(start ([^,)]+)(?:, target [^)]+)?\)\s*$")


def _phases(text: str | None) -> dict:
    """"operators 0.001, solve 2.732, search 0.011" -> {"operators": 0.001, ...}."""
    phases = {}
    for part in (text or "").split(","):
        name, _, value = part.strip().rpartition(" ")
        try:
            phases[name] = float(value)
        except ValueError:
            continue
    return phases


def parse_log(log: Path) -> tuple[str, float, list[list[dict]]]:
    """(label and seconds of the body solvers' set-up, iterations of every load step) from the log of
    a verbose run; an iteration's ``krylov`` is its GMRES line (None on the direct path)."""
    label, set_up, steps, krylov = None, None, [], None
    for line in log.read_text().splitlines():
        if set_up is None and (match := BODY_SETUP_LINE.match(line)):
            label, set_up = match[1], float(match[2])
        elif LOAD_STEP_LINE.match(line):
            steps.append([])
        elif match := KRYLOV_LINE.match(line):
            krylov = {"iterations": int(match[2]) + (krylov or {}).get("iterations", 0),
                      "residuals": int(match[3]) + (krylov or {}).get("residuals", 0),
                      "relative_residual": float(match[4]),
                      "start": (krylov or {}).get("start", float(match[5])), "kind": match[1]}
        elif match := ITERATION_LINE.match(line):
            if not steps:  # a single load step prints no "load step" line
                steps.append([])
            steps[-1].append({"iteration": int(match[1]), "active_primary": int(match[2]),
                              "added": int(match[3]), "removed": int(match[4]), "seconds": float(match[5]),
                              "phases": _phases(match[6]), "krylov": krylov})
            krylov = None
    if set_up is None:
        raise RunFailed(f"{log}: no '... of the 2 bodies: X s' line (log format changed?)")
    return label, set_up, steps


def compliance_estimate(iterations: list[dict]) -> float:
    """Seconds of a step attributed to new responses to the multipliers (an estimate; direct path).

    An iteration that reuses every cached column costs about the step's median
    iteration (dense Schur complement, two solves per body, contact checks); the
    time above that median is counted as the solves for the nodes that became
    active for the first time.
    """
    seconds = [i["seconds"] for i in iterations]
    if not seconds:
        return 0.0
    typical = statistics.median(seconds)
    return sum(max(0.0, t - typical) for t in seconds)


def krylov_counts(iterations: list[dict]) -> list[int] | None:
    """GMRES iterations of each active-set iteration of a step (None if the run logged none)."""
    counts = [i["krylov"]["iterations"] for i in iterations if i.get("krylov")]
    return counts if counts and len(counts) == len(iterations) else None


def body_solves(iterations: list[dict]) -> int | None:
    """Solves per body of a step's loop: per active-set iteration z = K^-1 f, the GMRES iterations
    and the residual products (interface_krylov.rs); None without the GMRES lines."""
    if krylov_counts(iterations) is None or any("residuals" not in i["krylov"] for i in iterations):
        return None
    return sum(1 + i["krylov"]["iterations"] + i["krylov"]["residuals"] for i in iterations)


def run_ours(binary: Path, case: Path, output: Path, path: str) -> dict:
    """One internodes contact solve, with -vv: the log has every step's iterations, their phases and
    their GMRES solves (``parse_log``)."""
    shutil.rmtree(output, ignore_errors=True)  # never read a stale summary
    log = output.with_suffix(".log")
    ranks = PATHS[path].get("ranks", 1)
    oversubscribe = ["--oversubscribe"] if ranks > (os.cpu_count() or 1) else []
    launcher = [MPIRUN, *oversubscribe, "-n", str(ranks)] if ranks > 1 else []
    usage = measure([*launcher, binary, "solve", case, "-vv", "--output", output], log,
                    env=MPI_ENV if ranks > 1 else None, max_seconds=MAX_SECONDS_OURS[path],
                    max_rss_gb=MAX_RSS_GB, check=False)
    summary_file = output / "summary.json"
    if not summary_file.is_file():  # an error before the result files: no timings
        tail = " | ".join(log.read_text().strip().splitlines()[-3:])
        raise RunFailed(f"exit status {usage['exit_status']}: {tail}")
    summary = json.loads(summary_file.read_text())
    if ranks > 1:  # mpirun's own rusage is one process's: the ranks' own peaks, summed, replace it
        if summary.get("ranks") != ranks or len(summary.get("rank_peak_memory_mb") or []) != ranks:
            raise RunFailed(f"{summary_file}: not a run on {ranks} ranks")
        usage |= {"peak_mb_mpirun": usage["peak_mb"], "peak_mb": sum(summary["rank_peak_memory_mb"]),
                  "rank_peak_mb": summary["rank_peak_memory_mb"]}
    contact = summary["contact"]
    # The coupled solver asked for (contact.settings.solver); the ones that ran are
    # contact.linear_solvers (interface, body, and a GMRES failure that moved auto to schur).
    solver = contact.get("settings", {}).get("solver")
    if solver != PATHS[path]["solver"]:
        raise RunFailed(f"{summary_file}: the run used the coupled solver {solver!r}, not {PATHS[path]['solver']!r}")
    phases = dict(summary["timings"])
    label, body_setup, iterations = parse_log(log)
    # The log and the summary must tell the same story.
    if [len(s) for s in iterations] != [s["iterations"] for s in contact["steps"]] or any(
            abs(logged["seconds"] - sum(i["seconds"].values())) > 2e-3
            for logged, i in zip(iterations[-1], contact["iterations"])):
        raise RunFailed(f"{log}: the iterations in the log do not match summary.json (log format changed?)")
    # GMRES iterations of the last step: summary.json's krylov_iterations where the binary writes them.
    for logged, record in zip(iterations[-1], contact["iterations"]):
        if record.get("krylov_iterations") is not None:
            logged["krylov"] = dict(logged["krylov"] or {}, iterations=int(record["krylov_iterations"]))
    bodies = {b["name"]: b for b in summary["bodies"]}
    assembly = sum(t for b in bodies.values() for phase, t in b["solve"]["timings"]
                   if phase in ("sparsity pattern", "assemble stiffness", "assemble loads",
                                "apply Dirichlet conditions"))
    steps = []
    for record, its in zip(contact["steps"], iterations):
        last = its[-1]
        steps.append({"load_factor": record["load_factor"], "status": record["status"],
                      "iterations": its, "seconds": phases[f"contact step {record['step']}"],
                      "compliance_estimate": compliance_estimate(its) if path == "direct" else None,
                      "active_primary": last["active_primary"],
                      "force": record["force_primary"][-1], "hertz_a": record["hertz_a"]})
    # The pairs' surfaces, a phase of their own since the binary of this line (outside every
    # phase before).
    set_up = phases["contact set-up"] + phases.get("contact surfaces", 0.0)
    linear = contact.get("linear_solvers") or {}
    # How many times each body's block was applied over the whole solve (coupled solve only: an AMG
    # V-cycle per application on cg-amg bodies, a pair of triangular solves on Cholesky; absent before).
    applications = linear.get("body_applications")
    if not (isinstance(applications, list) and applications and all(isinstance(n, int) for n in applications)):
        applications = None
    kinds = {i["krylov"].get("kind") for s in iterations for i in s if i.get("krylov") and i["krylov"].get("kind")}
    return usage | {
        "path": path, "solver": solver,
        "resolved": {"solver": linear.get("interface"), "body_solver": linear.get("body"),
                     "krylov_failure": linear.get("krylov_failure")},
        "body_applications": dict(zip(bodies, applications)) if applications else None,
        "krylov_kind": "coupled" if "coupled" in kinds else "interface" if kinds else None,
        "contact_status": contact["status"],
        "dofs": {name: b["num_dofs"] for name, b in bodies.items()},
        "stiffness_nnz": {name: b["solve"]["stiffness_nnz"] for name, b in bodies.items()},
        "read_mesh": phases["read mesh"],
        "set_up": set_up, "assembly": assembly, "body_setup": body_setup, "body_setup_label": label,
        "other_set_up": set_up - assembly - body_setup,
        "steps": steps,
        "contact_total": set_up + sum(s["seconds"] for s in steps),
        "write_output": phases["write output"],
        "internal_total": phases["total"],
    }


def rank_agreement(serial: Path, parallel: Path) -> dict:
    """The 2-rank run against the serial one, from their result files: the largest displacement and
    pressure differences over the largest values, the force difference per step over the force, and
    whether the active sets are the same node for node."""
    import h5py
    with h5py.File(serial / "solution.h5") as a, h5py.File(parallel / "solution.h5") as b:
        def relative(name: str) -> float:
            x, y = np.asarray(a[name]), np.asarray(b[name])
            return float(np.abs(x - y).max() / max(np.abs(x).max(), 1e-300))
        same_active = bool(np.array_equal(np.asarray(a["fields/contact_active"]), np.asarray(b["fields/contact_active"])))
        fields = {"displacement": relative("fields/displacement"), "pressure": relative("fields/contact_pressure")}
    steps_a, steps_b = (json.loads((d / "summary.json").read_text())["contact"]["steps"] for d in (serial, parallel))
    force = max(abs(s["force_primary"][-1] - t["force_primary"][-1]) / abs(s["force_primary"][-1])
                for s, t in zip(steps_a, steps_b))
    return fields | {"force": force, "same_active_set": same_active,
                     "same_statuses": [s["status"] for s in steps_a] == [t["status"] for t in steps_b]}


def agreement_lines(sizes: list[dict]) -> list[str]:
    """The report's bullets: each size's runs on several ranks against the serial one."""
    lines = []
    for size in sizes:
        for path in RANK_PATHS:
            for one in ("one", "steps"):
                q = size["runs"].get(f"{path}_{one}", {}).get("vs_serial")
                if q:
                    lines.append(_agreement_line(size, path, one, q))
    return lines or ["* no size has both runs"]


def _agreement_line(size: dict, path: str, one: str, q: dict) -> str:
    """One bullet of ``agreement_lines``."""
    return (f"* {size['name']}, {PATHS[path]['ranks']} ranks, {_kind(f'{path}_{one}')}: "
            f"displacement {q['displacement']:.1e}, contact pressure {q['pressure']:.1e}, force {q['force']:.1e} "
            f"(largest over the steps); active set {'the same' if q['same_active_set'] else 'DIFFERENT'}, "
            f"statuses {'the same' if q['same_statuses'] else 'DIFFERENT'}")


def dolfinx_seconds(count: int) -> float:
    """The time limit of a dolfinx run at a mesh of ``count`` DOFs."""
    return MAX_SECONDS_DOLFINX_LARGE if count > 1_500_000 else MAX_SECONDS_DOLFINX


def run_dolfinx(solver: str, case: Path, output: Path, count: int, ranks: int = 1) -> dict:
    """One dolfinx elastic solve (this script with --worker), one BLAS thread per process; on ``ranks``
    MPI ranks through mpirun when ranks > 1 (then the timings are rank 0's after a barrier per phase,
    and the peak memory and CPU time the sums over the ranks, as the worker reports them)."""
    result = output.with_suffix(".json")
    result.unlink(missing_ok=True)
    command = [sys.executable, __file__, "--worker", solver, "--case", case, "--output", result]
    env = dict(SERIAL_ENV)
    if ranks > 1:
        command = [MPIRUN, "-n", str(ranks), *command]
        env |= MPI_ENV
    usage = measure(command, output.with_suffix(".log"), env=env, max_seconds=dolfinx_seconds(count),
                    max_rss_gb=MAX_RSS_GB)
    data = json.loads(result.read_text())
    if ranks > 1:  # mpirun's own rusage is one process's: the worker's sums over the ranks replace it
        usage |= {"peak_mb_mpirun": usage["peak_mb"], "peak_mb": data["peak_mb_sum"], "cpu": data["cpu_sum"]}
    return usage | data


def _done_line(run: dict) -> str:
    """What a finished run of ours prints."""
    counts = [krylov_counts(s["iterations"]) for s in run["steps"]]
    gmres = "" if None in counts else f", {' + '.join(str(sum(c)) for c in counts)} GMRES iterations"
    return (f"{run['wall']:.1f} s, {run['peak_mb']:.0f} MB, {run['contact_status']} "
            f"({' + '.join(str(len(s['iterations'])) for s in run['steps'])} iterations{gmres})")


# MUMPS at 216,537 DOFs in the report of 2026-11-26 (wall of the run, about): the estimate's start when this
# run has no MUMPS figure (e.g. --sizes 3M alone).
MUMPS_MEASURED = {"dofs": 216_537, "wall": 35.0}


def mumps_not_run_reason(count: int, earlier: list[dict]) -> str | None:
    """Why dolfinx's MUMPS is not run at ``count`` DOFs: its time, grown like n^2 (a 3D factorization's
    work) from the largest size of this run where it finished (else MUMPS_MEASURED), beyond its time limit
    (None: it is run)."""
    done = [s for s in earlier if timed(s["runs"].get("dolfinx_mumps", {"not_run": ""}))]
    if done:
        largest = max(done, key=dofs)
        seconds, at, where = largest["runs"]["dolfinx_mumps"]["wall"], dofs(largest), "in this run"
    elif count > 1_500_000:
        seconds, at, where = MUMPS_MEASURED["wall"], MUMPS_MEASURED["dofs"], "in the report of 2026-11-26"
    else:
        return None
    estimate = seconds * (count / at) ** 2
    limit = dolfinx_seconds(count)
    if estimate <= limit:
        return None
    return (f"MUMPS took {seconds:.0f} s at {at:,} DOFs {where}; grown like n^2 to {count:,} DOFs, "
            f"about {estimate:,.0f} s, beyond the {limit:.0f} s limit (CG + GAMG is dolfinx's best there)")


def benchmark_size(size: Size, binary: Path, paths: list[str], earlier: list[dict],
                   one_step_only: bool = False) -> dict:
    """Mesh, the runs one after the other, and the CG / MUMPS agreement (``earlier``: the sizes done)."""
    generate_mesh(size)
    count = 3 * mesh_nodes(size.mesh)
    runs: dict[str, dict] = {}
    for run, (label, path, steps) in RUNS.items():
        if path and path not in paths:
            runs[run] = {"not_run": f"not selected (--paths {','.join(paths)})"}
        elif path and steps == LOAD_STEPS and one_step_only:
            runs[run] = {"not_run": "not selected (--one-step-only: the load-stepped run was left out for time)"}
        elif path and (reason := not_run_reason(path, count)):
            runs[run] = {"not_run": reason}
        elif run == "dolfinx_mumps" and (reason := mumps_not_run_reason(count, earlier)):
            runs[run] = {"not_run": reason}
        if "not_run" in runs.get(run, {}):
            print(f"   {label}: not run ({runs[run]['not_run']})", flush=True)
            continue
        print(f"   {label} ...", end=" ", flush=True)
        case = write_case(size, run, steps or ONE_STEP, path)
        output = size.folder / run
        try:
            if path:
                runs[run] = run_ours(binary, case, output, path)
                print(_done_line(runs[run]), flush=True)
            else:
                ranks = MPI_RANKS if run == "dolfinx_cg_mpi" else 1
                runs[run] = run_dolfinx("mumps" if run == "dolfinx_mumps" else "cg", case, output, count, ranks)
                print(f"{runs[run]['wall']:.1f} s, {runs[run]['peak_mb']:.0f} MB"
                      + (" (sum over the ranks)" if ranks > 1 else "")
                      + f", elastic solve {runs[run]['elastic_total']:.2f} s"
                      + (f" ({runs[run]['iterations']} CG iterations)" if run != "dolfinx_mumps" else ""), flush=True)
        except (RunFailed, OSError, KeyError, ValueError, IndexError, TypeError) as error:
            runs[run] = {"error": f"{type(error).__name__}: {error}"}
            print(f"FAILED ({runs[run]['error']})", flush=True)
    if timed(runs["dolfinx_cg"]) and timed(runs["dolfinx_mumps"]):
        u_cg, u_mumps = (np.load(size.folder / f"{r}.u.npy") for r in ("dolfinx_cg", "dolfinx_mumps"))
        runs["dolfinx_cg"]["l2_vs_mumps"] = float(np.linalg.norm(u_cg - u_mumps) / np.linalg.norm(u_mumps))
    for path in RANK_PATHS:  # our runs on several ranks against the serial one: the same answer?
        for one in ("one", "steps"):
            serial_run, parallel_run = runs.get(f"default_{one}", {}), runs.get(f"{path}_{one}", {})
            if timed(serial_run) and timed(parallel_run):
                parallel_run["vs_serial"] = rank_agreement(size.folder / f"default_{one}",
                                                           size.folder / f"{path}_{one}")
    if timed(runs["dolfinx_cg"]) and timed(runs["dolfinx_cg_mpi"]):  # the same solution, other DOF order
        norm = float(np.linalg.norm(np.load(size.folder / "dolfinx_cg.u.npy")))
        runs["dolfinx_cg_mpi"]["norm_vs_serial"] = abs(runs["dolfinx_cg_mpi"]["solution_norm"] - norm) / norm
    return {"name": size.name, "level": size.level, "mesh": str(size.mesh.relative_to(REPO)),
            "nodes": count // 3, "runs": runs}


# ---------------------------------------------------------------------------
# The dolfinx worker: one elastic solve of both bodies (a separate process per run)
# ---------------------------------------------------------------------------


def dolfinx_worker(solver: str, case_path: Path, output: Path) -> None:
    """Assemble and solve both bodies as one elastic problem; timings to ``output`` (JSON, .u.npy).
    Under mpirun (more than one rank): dolfinx_parallel_elastic.worker, the same problem and phases."""
    from mpi4py import MPI

    if MPI.COMM_WORLD.size > 1:
        from dolfinx_parallel_elastic import worker

        worker(solver, case_path, output, CG_RTOL)
        return
    from dolfinx import fem
    from petsc4py import PETSc

    from benchmark import assemble_and_solve
    from dolfinx_reference import COMPONENTS, Body, Dirichlet, ReferenceModel

    timings = {}
    clock = time.perf_counter()

    def lap(phase: str) -> None:
        """Time since the previous lap, stored under ``phase``."""
        nonlocal clock
        timings[phase] = time.perf_counter() - clock
        clock = time.perf_counter()

    # a. Mesh (both volumes in one dolfinx mesh) and the bodies of the case file.
    data = tomllib.loads(case_path.read_text())
    bodies = []
    for b in data["body"]:
        if b.get("load") or b.get("body_force"):
            raise RunFailed(f"{case_path}: the benchmark expects Dirichlet data only (body {b['name']})")
        dirichlet = [Dirichlet(d["group"], tuple(d.get(c) for c in COMPONENTS)) for d in b.get("dirichlet", [])]
        bodies.append(Body(b["name"], float(b["youngs_modulus"]), float(b["poisson_ratio"]), dirichlet=dirichlet))
    model = ReferenceModel(case_path.parent / data["mesh"], {})
    lap("mesh")
    # b. Forms: the sum of both bodies' elastic forms, no coupling between them.
    a = fem.form(sum((model.stiffness_form(b) for b in bodies[1:]), model.stiffness_form(bodies[0])))
    L = fem.form(sum((model.load_form(b) for b in bodies[1:]), model.load_form(bodies[0])))
    lap("form compilation")
    # c. Dirichlet conditions (every component prescribed on each group).
    bcs = []
    for body in bodies:
        for d in body.dirichlet:
            if any(v is None for v in d.values):
                raise RunFailed("the benchmark expects fully prescribed Dirichlet groups")
            dofs = fem.locate_dofs_topological(model.V, model.dim - 1, model.facets(d.group))
            bcs.append(fem.dirichletbc(np.array(d.values, dtype=PETSc.ScalarType), dofs, model.V))
    lap("boundary conditions")
    A, b, x, ksp, r = assemble_and_solve(solver, a, L, bcs, model, lap)
    np.save(output.with_suffix(".u.npy"), x.array)
    output.write_text(json.dumps({
        "timings": timings, "assemble": timings["assemble"], "solver_total": timings["setup"] + timings["solve"],
        "elastic_total": timings["assemble"] + timings["setup"] + timings["solve"],
        "iterations": ksp.getIterationNumber(), "relative_residual": r.norm() / b.norm(),
        "matrix_nnz": int(A.getInfo()["nz_used"]), "dofs": A.getSize()[0]}, indent=2))


# ---------------------------------------------------------------------------
# Step 3: tables and report
# ---------------------------------------------------------------------------


def best_dolfinx(runs: dict) -> str | None:
    """The faster dolfinx run (assembly + setup + solve)."""
    done = [r for r in ("dolfinx_cg", "dolfinx_mumps") if timed(runs[r])]
    return min(done, key=lambda r: runs[r]["elastic_total"], default=None)


def all_iterations(ours: dict) -> list[float]:
    """Seconds of every active-set iteration of every load step."""
    return [i["seconds"] for s in ours["steps"] for i in s["iterations"]]


def dofs(size: dict) -> int:
    """DOFs of both bodies: 3 x the mesh's nodes."""
    return 3 * size["nodes"]


def ratios(size: dict, path: str) -> dict:
    """The aims' figures of one path at one size (missing when a run did not finish).

    total: one-step contact total / dolfinx best; body_setup: the one-step run's body solver set-up /
    dolfinx best; steps_total: the load-stepped run's set-up + both steps / dolfinx best; step: extra
    step / (set-up + first step) and step_loop: extra step / first step, of the load-stepped run;
    iterations: the most active-set iterations of a load step (both runs); memory: the larger peak of
    the two runs / the peak of dolfinx's best run. The aims' own figures: total_cg (steps_total_cg): the
    one-step (load-stepped) contact total / the serial dolfinx CG + GAMG elastic solve; total_mpi: the same
    against dolfinx CG + GAMG on MPI_RANKS ranks; memory_cg: the larger peak / the serial CG run's;
    applications (applications_steps): the most body applications of a body over the one-step
    (load-stepped) run / dolfinx's CG iterations (the binary's body_applications, else absent).
    """
    runs, out = size["runs"], {}
    one, stepped, best = runs[f"{path}_one"], runs[f"{path}_steps"], best_dolfinx(runs)
    cg, mpi = runs["dolfinx_cg"], runs.get("dolfinx_cg_mpi", {"not_run": ""})
    peaks = [r["peak_mb"] for r in (one, stepped) if timed(r)]
    if timed(cg):
        if timed(one):
            out["total_cg"] = one["contact_total"] / cg["elastic_total"]
        if timed(stepped):
            out["steps_total_cg"] = stepped["contact_total"] / cg["elastic_total"]
        if peaks:
            out["memory_cg"] = max(peaks) / cg["peak_mb"]
        for key, run in (("applications", one), ("applications_steps", stepped)):
            if timed(run) and run.get("body_applications") and cg.get("iterations"):
                out[key] = max(run["body_applications"].values()) / cg["iterations"]
    if timed(mpi) and timed(one):
        out["total_mpi"] = one["contact_total"] / mpi["elastic_total"]
    if best:
        elastic = runs[best]["elastic_total"]
        if timed(one):
            out["total"] = one["contact_total"] / elastic
            out["body_setup"] = one["body_setup"] / elastic
        if timed(stepped):
            out["steps_total"] = stepped["contact_total"] / elastic
        peaks = [r["peak_mb"] for r in (one, stepped) if timed(r)]
        if peaks:
            out["memory"] = max(peaks) / runs[best]["peak_mb"]
    if timed(stepped) and len(stepped["steps"]) > 1:
        first, extra = stepped["steps"][0]["seconds"], max(s["seconds"] for s in stepped["steps"][1:])
        out["step"] = extra / (stepped["set_up"] + first)
        out["step_loop"] = extra / first
    counts = [len(s["iterations"]) for r in (one, stepped) if timed(r) for s in r["steps"]]
    if counts:
        out["iterations"] = max(counts)
    return out


def _verdict(value: float, aim: float) -> str:
    """"met, 0.72x the bound" or "missed, 2.2x the bound"."""
    return ("met" if value <= aim else "missed") + f", {value / aim:.2g}x the bound"


def _iterations_verdict(count: int) -> str:
    """"met" or "missed by N"."""
    return "met" if count <= AIM_ITERATIONS else f"missed by {count - AIM_ITERATIONS}"


def _kind(run: str) -> str:
    """"one step (1.0)" or "load steps (0.5, 1.0)"."""
    return RUNS[run][0].split(", ", 1)[1]


def _status_cell(run: dict) -> str:
    """The status column: the status, and the error of a run that did not finish."""
    if "not_run" in run:
        return "not run (below)"
    return f"{status(run)}: {run['error']}" if "error" in run else status(run)


def _steps_cell(step: dict) -> str:
    """"12.3 (18)" or "12.3 (18, cycling)"."""
    return f"{fmt(step['seconds'])} ({len(step['iterations'])}" + \
        ("" if step["status"] == "converged" else f", {step['status']}") + ")"


def contact_table(sizes: list[dict]) -> list[list[str]]:
    """Our contact solves: one row per size, path and run."""
    rows = [["DOFs (sphere + block)", "path", "run", "active primary nodes", "set-up: asm + solvers + other",
             "step 1 (its)", "step 2 (its)", "per iteration: mean / median", "compliance (est.)",
             "contact total", "wall", "peak MB", "status"]]
    for size in sizes:
        for run in OURS:
            r, path = size["runs"][run], RUNS[run][1]
            if not timed(r):
                rows.append([f"{dofs(size):,}", path, _kind(run), *["-"] * 9, _status_cell(r)])
                continue
            steps = r["steps"]
            its = all_iterations(r)
            if path == "direct":
                compliance = sum(s["compliance_estimate"] for s in steps)
                compliance_cell = f"{fmt(compliance)} ({compliance / sum(s['seconds'] for s in steps):.0%} of steps)"
            else:
                compliance_cell = "-"
            rows.append([
                f"{sum(r['dofs'].values()):,} ({' + '.join(f'{d:,}' for d in r['dofs'].values())})", path,
                _kind(run), f"{steps[-1]['active_primary']}",
                f"{fmt(r['set_up'])} = {fmt(r['assembly'], 2)} + {fmt(r['body_setup'])} + {fmt(r['other_set_up'], 2)}",
                _steps_cell(steps[0]), _steps_cell(steps[1]) if len(steps) > 1 else "-",
                f"{fmt(statistics.mean(its))} / {fmt(statistics.median(its))}", compliance_cell,
                fmt(r["contact_total"]), fmt(r["wall"]), f"{r['peak_mb']:.0f}", _status_cell(r)])
    return rows


def comparison_table(sizes: list[dict]) -> list[list[str]]:
    """dolfinx's elastic solve of the same mesh and, per path, our contact total against it."""
    rows = [["DOFs", "dfx asm", "dfx CG+GAMG setup+solve (its)", "dfx MUMPS setup+solve", "dfx best total",
             "dfx MB (CG / MUMPS)", f"dfx CG {MPI_RANKS} ranks: asm + setup+solve = total (its)",
             f"dfx CG {MPI_RANKS} ranks MB (sum)",
             *[f"{path}: contact / dfx best, one step (load steps)" for path in PATHS]]]
    for size in sizes:
        runs = size["runs"]
        cg, mumps, best = runs["dolfinx_cg"], runs["dolfinx_mumps"], best_dolfinx(runs)
        mpi = runs.get("dolfinx_cg_mpi", {"not_run": "not in results.json"})
        assembly = [r["assemble"] for r in (cg, mumps) if timed(r)]

        def ratio(path: str) -> str:
            q, one, stepped = ratios(size, path), runs[f"{path}_one"], runs[f"{path}_steps"]
            if "not_run" in one and "not_run" in stepped:
                return "not run"
            cells = []
            for key, run in (("total", one), ("steps_total", stepped)):
                mark = "" if status(run) == "ok" else f", {status(run)}"
                cells.append(f"{q[key]:.1f}{mark}" if key in q else status(run) if status(run) != "ok" else "-")
            return f"{cells[0]} ({cells[1]})"

        rows.append([
            f"{dofs(size):,}", fmt(min(assembly)) if assembly else "-",
            f"{fmt(cg['solver_total'])} ({cg['iterations']})" if timed(cg) else status(cg),
            fmt(mumps["solver_total"]) if timed(mumps) else status(mumps),
            f"{fmt(runs[best]['elastic_total'])} ({'CG' if best == 'dolfinx_cg' else 'MUMPS'})" if best else "-",
            " / ".join(f"{r['peak_mb']:.0f}" if timed(r) else "-" for r in (cg, mumps)),
            f"{fmt(mpi['assemble'])} + {fmt(mpi['solver_total'])} = {fmt(mpi['elastic_total'])} ({mpi['iterations']})"
            if timed(mpi) else status(mpi),
            f"{mpi['peak_mb']:.0f}" if timed(mpi) else "-",
            *[ratio(path) for path in PATHS]])
    return rows


def _judged(value: float, aim: float, judged: bool, below: str) -> str:
    """"1.3: met, 0.65x the bound", or "1.3: not judged below 99k"."""
    return f"{value:.2f}: " + (_verdict(value, aim) if judged else f"not judged below {below}")


def aims_table(sizes: list[dict]) -> list[list[str]]:
    """The aims per size and path: the figure, met or missed and by how much."""
    rows = [["DOFs", "path", f"1. contact / dfx CG serial (<= {AIM_TOTAL:g} at >= 99k)",
             f"1'. contact / dfx CG {MPI_RANKS} ranks (no aim)",
             f"2. peak MB / dfx CG serial's (<= {AIM_MEMORY:g} at >= 1M)",
             f"3. body applications / dfx CG its (<= {AIM_APPLICATIONS:g})",
             f"4. most iterations in a step (<= {AIM_ITERATIONS})",
             f"5. step 2 / (set-up + step 1) (<= {AIM_STEP:g})"]]
    for size in sizes:
        for path in PATHS:
            runs = [size["runs"][f"{path}_{kind}"] for kind in ("one", "steps")]
            if all("not_run" in r for r in runs):
                rows.append([f"{dofs(size):,}", path, *["not run"] * 6])
                continue
            q = ratios(size, path)
            missing = [status(r) if status(r) != "ok" else "-" for r in runs]  # one step, load steps
            applications = "-"
            if "applications" in q or "applications_steps" in q:
                applications = (_judged(q["applications"], AIM_APPLICATIONS, True, "") if "applications" in q
                                else missing[0] if missing[0] != "-" else "n/a")
                if "applications_steps" in q:
                    applications += f" (load steps {q['applications_steps']:.2f})"
            elif any(timed(r) for r in runs):
                applications = "n/a (no body_applications in summary.json)"
            rows.append([f"{dofs(size):,}", path,
                         _judged(q["total_cg"], AIM_TOTAL, dofs(size) >= AIM_TOTAL_MIN_DOFS, "99k")
                         if "total_cg" in q else missing[0],
                         f"{q['total_mpi']:.2f}" if "total_mpi" in q else "-",
                         _judged(q["memory_cg"], AIM_MEMORY, dofs(size) >= AIM_MEMORY_MIN_DOFS, "1M")
                         if "memory_cg" in q else "-",
                         applications,
                         f"{q['iterations']}: {_iterations_verdict(q['iterations'])}" if "iterations" in q else "-",
                         f"{q['step']:.2f}: {_verdict(q['step'], AIM_STEP)}" if "step" in q else missing[1]])
    return rows


def rank_table(sizes: list[dict]) -> list[list[str]]:
    """Aim 6: the one-step run on 1, 2 and 4 ranks: wall time and the peak of each rank, against the serial
    (default path) run's."""
    rows = [["DOFs", "ranks", "wall s", "wall / serial", "contact total s", "peak MB of each rank",
             "largest rank / serial peak", "aims (6)"]]
    for size in sizes:
        serial = size["runs"]["default_one"]
        for path in ("default", *RANK_PATHS):
            run = size["runs"][f"{path}_one"]
            ranks = PATHS[path].get("ranks", 1)
            if not timed(run) or not timed(serial):
                rows.append([f"{dofs(size):,}", f"{ranks}", *["-"] * 5, status(run)])
                continue
            peaks = run.get("rank_peak_mb") or [run["peak_mb"]]
            wall, peak = run["wall"] / serial["wall"], max(peaks) / serial["peak_mb"]
            judged = dofs(size) >= AIM_MEMORY_MIN_DOFS
            verdicts = []
            if ranks in AIM_RANK_PEAK:
                verdicts.append(f"peak <= {AIM_RANK_PEAK[ranks]:g}: " + (
                    _verdict(peak, AIM_RANK_PEAK[ranks]) if judged else "not judged below 1M"))
            if ranks in AIM_RANK_WALL:
                verdicts.append(f"wall <= {AIM_RANK_WALL[ranks]:g}: " + (
                    _verdict(wall, AIM_RANK_WALL[ranks]) if judged else "not judged below 1M"))
            elif ranks > (os.cpu_count() or 1):
                verdicts.append("wall not judged (oversubscribed)")
            rows.append([f"{dofs(size):,}", f"{ranks}", fmt(run["wall"]), f"{wall:.2f}", fmt(run["contact_total"]),
                         " / ".join(f"{p:.0f}" for p in peaks), f"{peak:.2f}", "; ".join(verdicts) or "-"])
    return rows


def iteration_table(sizes: list[dict]) -> list[list[str]]:
    """Every load step of our runs: its iterations' times (first, second, the rest) and GMRES iterations."""
    rows = [["DOFs", "path", "run", "step (factor)", "status", "iterations", "active at the end", "1st it",
             "2nd it", "others: median / max", "step", "compliance (est.)", "GMRES its: sum / max",
             "GMRES its per iteration", "contact force", "Hertz a"]]
    for size in sizes:
        for run in OURS:
            r = size["runs"][run]
            if not timed(r):
                continue
            for k, s in enumerate(r["steps"], start=1):
                t = [i["seconds"] for i in s["iterations"]]
                rest = t[2:]
                counts = krylov_counts(s["iterations"])
                compliance = s.get("compliance_estimate")
                rows.append([f"{dofs(size):,}", RUNS[run][1], _kind(run),
                             f"{k} ({s['load_factor']:g})", s["status"], str(len(t)),
                             f"{s['active_primary']}", fmt(t[0]),
                             fmt(t[1]) if len(t) > 1 else "-",
                             f"{fmt(statistics.median(rest))} / {fmt(max(rest))}" if rest else "-",
                             fmt(s["seconds"]), fmt(compliance) if compliance is not None else "-",
                             f"{sum(counts)} / {max(counts)}" if counts else "-",
                             " ".join(map(str, counts)) if counts else "-",
                             f"{s['force']:.4g}", f"{s['hertz_a']:.3g}" if s["hertz_a"] else "-"])
    return rows


def _breakdown(size: dict, path: str) -> str:
    """Shares of the one-step run's contact total, by phase (from the log and summary.json)."""
    run = size["runs"][f"{path}_one"]
    cg = size["runs"]["dolfinx_cg"]
    reference = cg if timed(cg) else size["runs"][best_dolfinx(size["runs"])]
    total, elastic = run["contact_total"], reference["elastic_total"]
    loop = sum(s["seconds"] for s in run["steps"])
    count = sum(len(s["iterations"]) for s in run["steps"])
    if path == "direct":
        compliance = sum(s["compliance_estimate"] for s in run["steps"])
        return (f"{size['name']}: Cholesky of both bodies {run['body_setup'] / total:.0%} (alone "
                f"{run['body_setup'] / elastic:.1f}x dolfinx's whole solve), compliance solves (est.) "
                f"{compliance / total:.0%}, the other iteration work {(loop - compliance) / total:.0%} "
                f"({count} iterations), assembly {run['assembly'] / total:.0%}")
    its = [i for s in run["steps"] for i in s["iterations"]]
    solve = sum(i.get("phases", {}).get("solve", 0.0) for i in its)
    solves = [body_solves(s["iterations"]) for s in run["steps"]]
    text = (f"{size['name']}: body solver set-up ({run['body_setup_label']} of both bodies) "
            f"{run['body_setup'] / total:.0%}, "
            f"the iterations' solve phase ({'coupled GMRES' if run.get('krylov_kind') == 'coupled' else 'z = K^-1 f, GMRES'}) "
            f"{solve / total:.0%}")
    if run.get("body_applications") and solve > 0:
        kind = "Cholesky (pairs of triangular solves)" if (run.get("resolved") or {}).get("body_solver") == "cholesky" \
            else "AMG V-cycle"
        text += (f": {' + '.join(str(n) for n in run['body_applications'].values())} {kind} applications "
                 f"({' + '.join(run['body_applications'])}), dolfinx's CG took {reference.get('iterations', '?')} "
                 f"iterations")
    elif run.get("krylov_kind") != "coupled" and None not in solves and solve > 0:
        pair = solve / sum(solves)
        kind = "CG + AMG" if (run.get("resolved") or {}).get("body_solver") != "cholesky" else "Cholesky"
        text += (f": {sum(solves)} {kind} solves per body at {fmt(pair)} s per pair of bodies, "
                 f"{pair / elastic:.2f}x dolfinx's whole elastic solve (the aim's budget, {AIM_TOTAL:g}x that "
                 f"solve, is {AIM_TOTAL * elastic / pair:.0f} such pairs)")
    return (text + f"; the rest of the loop {(loop - solve) / total:.0%} ({count} iterations), assembly "
            f"{run['assembly'] / total:.0%}, other set-up {run['other_set_up'] / total:.0%}")


def _overshoot(size: dict, path: str) -> str:
    """Largest active set of the one-step run against its final one (primary nodes)."""
    its = size["runs"][f"{path}_one"]["steps"][0]["iterations"]
    largest, final = max(i["active_primary"] for i in its), its[-1]["active_primary"]
    return f"{size['name']}: {largest} active primary nodes at most, {final} at the end"


DIRECT_BOUND = (
    "The sparse Cholesky factorization grows faster than GAMG (factor work ~ n^2 in 3D with nested dissection, "
    "GAMG's ~ n): once it alone exceeds twice dolfinx's solve, the aim is out of reach for this path whatever "
    "the loop costs. The compliance solves are one forward + backward solve with each body's factor per "
    "multiplier (per active primary node, src/contact/coupled/compliance.rs); the second iteration pays most of them, "
    "because the unconstrained first iteration makes every geometrically overlapping node active at once, so "
    "columns are computed for more nodes than end in contact. The other iteration work (the dense Schur "
    "complement from the cached responses, its LU, the solves for z and the back-substitution, the interface "
    "operators and the contact checks) is paid at every iteration.")
COUPLED_BOUND = (
    "With the coupled solve every active-set iteration runs one right-preconditioned GMRES on the whole coupled "
    "system, each GMRES iteration applying each body's block once (one AMG V-cycle, or a pair of triangular "
    "solves on a Cholesky body) and the half-space approximation of the interface Schur complement: the loop costs "
    "about the body applications of aim 3 times one V-cycle, against dolfinx's CG iterations times one V-cycle "
    "(plus one matrix product each).")
ITERATIVE_BOUND = (
    "On the iterative path every active-set iteration solves the interface equation anew: z = K^-1 f, then one "
    "CG + AMG solve per body per GMRES iteration and per restart residual (src/contact/interface_krylov.rs), "
    "each pair of solves the fraction of dolfinx's whole elastic solve given above. The total is about the "
    "number of pairs times that fraction: the aim holds only if the whole loop makes no more pairs than the "
    "budget, whatever the set-up costs.")


DEFAULT_BOUND = (
    "The default path is the iterative one's solve (GMRES, loose on iterations that change the active set) on "
    "Cholesky factors below 30,000 DOFs in the larger body (older binaries: 250,000), where a body's block costs "
    "a pair of triangular solves, and on AMG above: its set-up is the factorization or the AMG hierarchy, and "
    "its loop the GMRES iterations.")


def reading(sizes: list[dict]) -> list[str]:
    """A reading of the figures, derived from them (one paragraph per point)."""
    text = []
    failed = [f"{RUNS[run][0]} at {s['name']}: {status(r)}" + (f" ({r['error']})" if "error" in r else "")
              for s in sizes for run in RUNS if status(r := s["runs"][run]) not in ("ok", "not run")]
    if failed:
        text.append("**Failures and stopped runs.** " + "; ".join(failed) + ". The times of a run of ours that "
                    "ended in a non-converged status are still reported (a step that does not settle stops the "
                    "load steps); a converged solve would have taken a different time.")
    not_run: dict[tuple, list[str]] = {}
    for s in sizes:
        for run in [*OURS, "dolfinx_mumps"]:
            if "not_run" in s["runs"][run]:
                path = RUNS[run][1] or "dolfinx MUMPS"
                not_run.setdefault((s["name"], path, s["runs"][run]["not_run"]), []).append(_kind(run))
    if not_run:
        text.append("**Not run.** " + "; ".join(f"The {path} path at {name} ({', '.join(kinds)}): {reason}"
                                                for (name, path, reason), kinds in not_run.items()) + ".")
    aims: dict[int, list[str]] = {}
    for path in PATHS:
        done = [s for s in sizes if "total_cg" in ratios(s, path)]
        if not done:
            continue
        parts = []
        for s in done:
            one, q = s["runs"][f"{path}_one"], ratios(s, path)
            cg, mpi = s["runs"]["dolfinx_cg"], s["runs"].get("dolfinx_cg_mpi", {"not_run": ""})
            judged = dofs(s) >= AIM_TOTAL_MIN_DOFS
            parts.append(f"{s['name']}: {fmt(one['contact_total'])} s against {fmt(cg['elastic_total'])} s, "
                         f"ratio {q['total_cg']:.2f}" + ("" if status(one) == "ok" else f" ({status(one)})")
                         + (f" (load steps: {q['steps_total_cg']:.2f})" if "steps_total_cg" in q else "")
                         + (f", {_verdict(q['total_cg'], AIM_TOTAL)}" if judged else ", not judged below 99k")
                         + (f"; against dolfinx on {MPI_RANKS} ranks ({fmt(mpi['elastic_total'])} s) "
                            f"{q['total_mpi']:.2f}" if "total_mpi" in q else ""))
        aims.setdefault(1, []).append(
                    f"**Aim 1, {path} path: contact total <= {AIM_TOTAL:g} x one serial dolfinx CG + GAMG elastic "
                    "solve, at >= 99k DOFs** (one-step run: set-up + its active-set loop + post-processing, against "
                    "dolfinx's assembly + GAMG set-up + CG solve; the ratio to the same dolfinx solve on "
                    f"{MPI_RANKS} MPI ranks is shown too, no aim). "
                    + "; ".join(parts) + ". What bounds it (shares of the one-step contact total): "
                    + "; ".join(_breakdown(s, path) for s in done) + ". "
                    + (DIRECT_BOUND if path == "direct" else
                       (COUPLED_BOUND if any(s["runs"][f"{path}_one"].get("krylov_kind") == "coupled" for s in done)
                        else ITERATIVE_BOUND if path == "iterative" else DEFAULT_BOUND)))
    aim2 = {}
    for path in PATHS:
        parts = []
        for s in [s for s in sizes if "step" in ratios(s, path)]:
            r, q = s["runs"][f"{path}_steps"], ratios(s, path)
            first, second = r["steps"][0], r["steps"][1]
            part = (f"{s['name']}: step 2 {fmt(second['seconds'])} s ({len(second['iterations'])} iterations, "
                    f"{second['status']}) against set-up + step 1 {fmt(r['set_up'] + first['seconds'])} s "
                    f"({fmt(r['set_up'])} + {fmt(first['seconds'])}, {len(first['iterations'])} iterations), ratio "
                    f"{q['step']:.2f}, {_verdict(q['step'], AIM_STEP)} (loops only: {q['step_loop']:.2f})")
            if path == "direct":
                part += f"; compliance (est.) {second['compliance_estimate'] / second['seconds']:.0%} of step 2"
            elif r.get("body_applications"):
                part += (f"; body applications over both steps "
                         f"{' + '.join(str(n) for n in r['body_applications'].values())}")
            elif r.get("krylov_kind") != "coupled" and \
                    None not in (solves := [body_solves(x["iterations"]) for x in (first, second)]):
                part += f"; {solves[1]} solves per body in step 2 against {solves[0]} in step 1"
            parts.append(part)
        if parts:
            aim2[path] = f"*{path}*: " + "; ".join(parts) + "."
    if aim2:
        why = {"direct": "Direct: the kept factors and cached responses save the set-up and the columns of step 1's "
                         "nodes, not the loop; step 2 needs columns for the new nodes (its second iteration).",
               "iterative": "Iterative: step 2 keeps the set-up (AMG hierarchies, operators), K^-1 f (scaled) and "
                            "GMRES' warm start from the previous tractions; each of its active-set iterations still "
                            "costs a GMRES solve (the solves per body above).",
               "default": "Default: as the iterative path, with the bodies' Cholesky factors below 30,000 DOFs in "
                          "the larger body (older binaries: 250,000).",
               "mpi2": "mpi2: as the default path, the bodies' rows and the coupled GMRES shared by 2 ranks (AMG "
                       "bodies at every size).",
               "mpi4": "mpi4: as mpi2 on 4 ranks (oversubscribed where the machine has fewer cores)."}
        aims[5] = [f"**Aim 5: each extra load step <= {AIM_STEP:g} x the first, the set-up counted in the first** "
                    "(load-stepped run: step 2 / (set-up + step 1)). " + " ".join(aim2.values()) + " What bounds it: "
                    "doubling the imposed displacement doubles the contact area (a^2 ~ R delta); step 2 starts from "
                    "step 1's active set, its first iteration makes the whole new overlap active and the loop again "
                    "sheds the nodes in tension, each iteration on a larger interface than in step 1. "
                    + " ".join(why[path] for path in aim2)]
    aim3, overshoot = [], []
    for path in PATHS:
        parts = []
        for s in [s for s in sizes if "iterations" in ratios(s, path)]:
            q = ratios(s, path)
            per_run = [f"{_kind(run).split(' (')[0]} "
                       + " + ".join(str(len(x["iterations"])) for x in s["runs"][run]["steps"])
                       for run in (f"{path}_one", f"{path}_steps") if timed(s["runs"][run])]
            parts.append(f"{s['name']}: at most {q['iterations']} ({', '.join(per_run)}), "
                         f"{_iterations_verdict(q['iterations'])}")
            if timed(s["runs"][f"{path}_one"]):
                overshoot.append(f"{path} {_overshoot(s, path)}")
        if parts:
            aim3.append(f"*{path}*: " + "; ".join(parts) + ".")
    if aim3:
        aims[4] = [f"**Aim 4: at most {AIM_ITERATIONS} active-set iterations per load step.** " + " ".join(aim3)
                    + " What sets the count: the unconstrained first iteration makes every geometrically "
                    "overlapping node active (one-step runs, " + "; ".join(overshoot) + "), then the loop removes "
                    "the nodes in tension a rim at a time, one iteration per rim: the count grows with the number "
                    "of rims between the overlap and the contact zone, i.e. with the refinement."]
    large = [s for s in sizes if dofs(s) >= AIM_MEMORY_MIN_DOFS]
    aim4 = []
    for path in PATHS:
        measured = [s for s in sizes if "memory_cg" in ratios(s, path)]
        parts = []
        for s in measured:
            q, cg = ratios(s, path), s["runs"]["dolfinx_cg"]
            peak = max(s["runs"][run]["peak_mb"] for run in (f"{path}_one", f"{path}_steps")
                       if timed(s["runs"][run]))
            parts.append(f"{s['name']}: {peak:.0f} MB against {cg['peak_mb']:.0f} MB, ratio {q['memory_cg']:.2f}"
                         + (f", {_verdict(q['memory_cg'], AIM_MEMORY)}" if dofs(s) >= AIM_MEMORY_MIN_DOFS else ""))
        missing = [s["name"] for s in large if s not in measured]
        if missing:
            parts.append(f"not measured at {', '.join(missing)} (not run or not finished there)")
        if parts:
            aim4.append(f"*{path}*: " + "; ".join(parts) + ".")
    if aim4:
        judged = ("" if large else f" No size of >= {AIM_MEMORY_MIN_DOFS:,} DOFs in this run: the aim is not judged; "
                  "the smaller sizes show the trend.")
        aims[2] = [f"**Aim 2: peak memory <= {AIM_MEMORY:g} x the serial dolfinx CG + GAMG run's at >= 1M DOFs** (the "
                    "larger of the path's two runs). " + " ".join(aim4) + judged + " What our process holds: "
                    "direct, the two Cholesky factors, which grow like n^(4/3) where dolfinx's CG + GAMG grows like "
                    "n, and the cached responses to the multipliers; iterative, each body's stiffness, its copy in "
                    "PETSc and the GAMG hierarchy, about linear in n like dolfinx's, plus the interface operators "
                    "and GMRES' basis. dolfinx's peak includes the Python interpreter, dolfinx and the gmsh model, "
                    "which weigh most at the small sizes."]
    aim3 = []
    for path in PATHS:
        parts = []
        for s in sizes:
            q, one, cg = ratios(s, path), s["runs"][f"{path}_one"], s["runs"]["dolfinx_cg"]
            if "applications" in q:
                counts = one["body_applications"]
                parts.append(f"{s['name']}: {' + '.join(f'{n} ({b})' for b, n in counts.items())} against "
                             f"{cg['iterations']} CG iterations, ratio {q['applications']:.2f}, "
                             f"{_verdict(q['applications'], AIM_APPLICATIONS)}"
                             + (f" (load steps: {q['applications_steps']:.2f})" if "applications_steps" in q else ""))
            elif timed(one):
                parts.append(f"{s['name']}: n/a (the binary wrote no body_applications)")
        if parts:
            aim3.append(f"*{path}*: " + "; ".join(parts) + ".")
    if aim3:
        aims[3] = [f"**Aim 3: body applications per body over the whole solve <= {AIM_APPLICATIONS:g} x dolfinx's CG "
                   "iterations** (`summary.json`'s `contact.linear_solvers.body_applications` of the one-step run: an "
                   "AMG V-cycle per application on cg-amg bodies, a pair of triangular solves on Cholesky ones; the "
                   "larger of the two bodies against the serial dolfinx CG + GAMG iterations, each one V-cycle). "
                   + " ".join(aim3)]
    for number in sorted(aims):
        text.extend(aims[number])
    gmres = []
    for s in sizes:
        counts = [c for run in ("iterative_one", "iterative_steps") if timed(s["runs"][run])
                  for x in s["runs"][run]["steps"] if (c := krylov_counts(x["iterations"]))]
        residuals = [i["krylov"]["relative_residual"] for run in ("iterative_one", "iterative_steps")
                     if timed(s["runs"][run]) for x in s["runs"][run]["steps"] for i in x["iterations"]
                     if i.get("krylov") and "relative_residual" in i["krylov"]]
        if counts:
            flat = [k for c in counts for k in c]
            gmres.append(f"{s['name']}: median {statistics.median(flat):g}, at most {max(flat)} per active-set "
                         f"iteration, {min(map(sum, counts))} to {max(map(sum, counts))} per step"
                         + (f", final relative residuals at most {max(residuals):.1e}" if residuals else ""))
    if gmres:
        text.append("**GMRES on the iterative path** (iterations per active-set iteration, from the log's "
                    "`interface GMRES` / `coupled GMRES` lines or summary.json's `krylov_iterations`; sums and "
                    "maxima of every step in "
                    "the last table): " + "; ".join(gmres) + ".")
    cores = [f"{s['name']} {RUNS[run][1]} {s['runs'][run]['cpu'] / s['runs'][run]['wall']:.2f}"
             for s in sizes for run in OURS if timed(s["runs"][run])]
    if cores:
        text.append(f"**Threads.** Our processes used {', '.join(cores)} CPU seconds per wall second (per size and "
                    "path, one step then load steps); the dolfinx runs are serial (one process, one BLAS thread). "
                    "On this shared 2-core machine a figure below 1 means the run waited for the CPU.")
    agreement = [s["runs"]["dolfinx_cg"]["l2_vs_mumps"] for s in sizes if "l2_vs_mumps" in s["runs"]["dolfinx_cg"]]
    ranks = [s["runs"]["dolfinx_cg_mpi"]["norm_vs_serial"] for s in sizes
             if "norm_vs_serial" in s["runs"].get("dolfinx_cg_mpi", {})]
    if agreement or ranks:
        text.append("**Sanity.** " + (f"dolfinx's CG + GAMG and MUMPS displacements differ by at most "
                                      f"{max(agreement):.1e} (relative L2; CG rtol {CG_RTOL:.0e}). " if agreement else "")
                    + (f"The {MPI_RANKS}-rank CG solution's norm differs from the serial one's by at most "
                       f"{max(ranks):.1e} (relative; another DOF numbering, so norms are compared)." if ranks else ""))
    return text


def _resolved(sizes: list[dict]) -> list[str]:
    """A bullet with the solvers the runs resolved (summary.json's contact.solver and contact.body_solver,
    where the binary writes them), or nothing."""
    names = {}
    for s in sizes:
        for run in OURS:
            resolved = s["runs"][run].get("resolved") or {}
            for key in ("solver", "body_solver"):
                if resolved.get(key) is not None:
                    value = resolved[key] if isinstance(resolved[key], str) else json.dumps(resolved[key])
                    names.setdefault(RUNS[run][1], {}).setdefault(key, set()).add(f"{value} ({s['name']})")
    if not names:
        return []
    return ["* Solvers that ran (`summary.json`'s `contact.linear_solvers`): " + "; ".join(
        f"{path}: " + ", ".join(f"{key} {' / '.join(sorted(values))}" for key, values in keys.items())
        for path, keys in names.items()) + "."]


def _load_range(sizes: list[dict]) -> str:
    """"min to max" of the load averages measured before the runs."""
    loads = [r["load_before"] for s in sizes for r in s["runs"].values() if "load_before" in r]
    return f"{min(loads):.1f} to {max(loads):.1f}" if loads else "not measured"


def _size_commits(sizes: list[dict], env: dict) -> str:
    """"; sizes measured at other commits: ..." when a --merge kept sizes of an earlier commit."""
    other = [f"{s['name']} at {s['commit']}" for s in sizes if s.get("commit", env["commit"]) != env["commit"]]
    return f"; sizes measured at an earlier commit: {', '.join(other)} (git log between them says what changed)" \
        if other else ""


def write_report(env: dict, sizes: list[dict], argv: list[str]) -> None:
    """validation/CONTACT_BENCHMARK.md: machine, versions, tables, reading, method."""
    env_rows = [["item", "value"], ["date", env["date"]],
                ["machine", f"{env['cpu']}, {env['nproc']} cores, {env['memory_gib']} GiB, {env['os']}"],
                ["internodes", f"{env['binary_version']} (commit {env['commit']}), built with {env['rustc']}"
                 + _size_commits(sizes, env)],
                ["dolfinx / PETSc", f"{env['dolfinx']} / {env['petsc']}"], ["BLAS", env["blas"]],
                ["gmsh", env["gmsh"]], ["command", f"`{COMMAND}` (this run: `{' '.join(argv)}`)"]]
    parameters = base_case()[1].get("geo_parameters", {})
    h_c = parameters.get("h_c", 1 / 15)  # the geo script's default: R / 15
    paths = "; ".join(f"*{name}*: `[solver] body = \"{p['body']}\"`, `[contact] solver = \"{p['solver']}\"` "
                      f"({p['label']})" for name, p in PATHS.items())
    text = [
        "# Contact benchmark: internodes against one dolfinx elastic solve",
        "",
        "Written by `validation/contact_benchmark.py`; do not edit by hand. Regenerate with",
        "",
        "```sh",
        COMMAND,
        "```",
        "",
        markdown(env_rows),
        "",
        "## Contact",
        "",
        "**Problem.** `geo/hemisphere_on_block.toml`: elastic hemisphere (R = 1) pushed by delta = 0.01 onto an "
        "elastic block (E = 1000, nu = 0.3 both), frictionless, contact radius a ~ 0.1 R; mesh "
        "`geo/hemisphere_on_block.geo` with the case's parameters ("
        + ", ".join(f"{k} = {v:g}" for k, v in parameters.items()) + ") at levels "
        + ", ".join(f"{s['level']} ({dofs(s):,} DOFs, h_c = R/{1 / (h_c * 2 ** -s['level']):.0f})" for s in sizes)
        + f". Ours: `internodes solve`, two paths: {paths}. Each path twice: the full displacement in one step "
        f"(*one step*) and with `[contact] load_steps = {list(LOAD_STEPS)}` (*load steps*). dolfinx: one linear "
        "elastic solve of the same two-body mesh (both volumes in one mesh, sphere_top displaced by "
        "(0, 0, -delta), block_base clamped, no contact coupling: two independent SPD problems), assembly + its "
        "faster solver.",
        "",
        "### Our contact solve",
        "",
        "Times in seconds (wall), memory in MB (peak resident set of the process).",
        "",
        markdown(contact_table(sizes)),
        "",
        *_resolved(sizes),
        "* *active nodes*: at the end of the last step; the frictionless multipliers are one per active primary "
        "node. *status*: how the last step ended (`cycling`: the active set came back to an earlier set).",
        "* *set-up* = `contact surfaces` + `contact set-up` of `summary.json`: *asm* (sparsity, stiffness, "
        "Dirichlet rows of both bodies) + *solvers* (the run log's `... of both bodies` line: direct, ordering + "
        "Cholesky; iterative, PETSc initialization + GAMG hierarchies) + *other* (the candidate surfaces with "
        "their bodies' boundaries, and the interpolation operators between them; the surfaces were outside "
        "every phase of binaries before 2026-12-05).",
        "* *step k* = the active-set loop of load step k with its post-processing (iterations); "
        "*per iteration* over the iterations of all steps; *compliance (est.)*, direct path only: per step, the "
        "iteration times above the step's median iteration, summed (the cost of new interface-compliance "
        "columns: an estimate, the solver does not time it separately; the iterative path computes no columns).",
        "* *contact total* = set-up + every step (no mesh reading, no output); *wall* = the whole process.",
        "",
        "### Against dolfinx",
        "",
        markdown(comparison_table(sizes)),
        "",
        "* *dfx asm* = `assemble_matrix(a, bcs)` + `A.assemble()` (the smaller of its two runs); *setup+solve*: "
        f"CG + GAMG (rtol {CG_RTOL:.0e}, rigid-body near-null space, iterations) or MUMPS Cholesky analysis + "
        "factorization + solve; *dfx best total* = the faster run's own assembly + setup + solve; serial, one "
        "BLAS thread. Peak memory includes the Python interpreter, dolfinx and the gmsh model.",
        "* *contact / dfx best*: our contact total (set-up + every step) over dolfinx's best total, the one-step "
        "run and in brackets the load-stepped one.",
        f"* *dfx CG {MPI_RANKS} ranks*: the same CG + GAMG solve under `mpirun -n {MPI_RANKS}` "
        "(validation/dolfinx_parallel_elastic.py: the mesh read by rank 0 and distributed by dolfinx; each phase "
        "ends with a barrier and is timed on rank 0); its memory is the sum of the ranks' peaks.",
        "",
        "### Ranks against one process",
        "",
        markdown(rank_table(sizes)),
        "",
        "* Aim 6, the one-step runs: the largest rank's peak resident memory (`summary.json`'s "
        f"`rank_peak_memory_mb`) at most {AIM_RANK_PEAK[2]:g} of the serial run's peak on 2 ranks and "
        f"{AIM_RANK_PEAK[4]:g} on 4, and the wall time on 2 ranks at most {AIM_RANK_WALL[2]:g} of the serial "
        "run's, judged at >= 1M DOFs. 4 ranks on a machine of fewer cores are oversubscribed: their memory "
        "counts, their time is shown only. What each rank's memory is made of: "
        "[MEMORY_MODEL.md](MEMORY_MODEL.md).",
        "",
        "Paths `mpi2` and `mpi4` against `default` on the same mesh, from their output files (largest "
        "difference over the largest value; the serial run's bodies are Cholesky below 30,000 DOFs, CG + AMG "
        "above, the runs on ranks always CG + AMG):",
        "",
        *agreement_lines(sizes),
        "",
        "### Aims",
        "",
        markdown(aims_table(sizes)),
        "",
        "* 1: the one-step run's contact total against the serial dolfinx CG + GAMG solve (assembly + set-up + "
        f"solve), judged at >= 99k DOFs; 1': the same against dolfinx on {MPI_RANKS} MPI ranks (`mpirun -n "
        f"{MPI_RANKS}`, the mesh read on rank 0 and distributed, rank 0's times after a barrier per phase), shown "
        "without an aim. 2: the larger peak of the path's two runs against the serial CG run's peak, judged at "
        f">= {AIM_MEMORY_MIN_DOFS:,} DOFs. 3: `contact.linear_solvers.body_applications` of the one-step run (the "
        "larger body; in brackets the load-stepped run) against dolfinx's CG iterations; n/a where the binary does "
        "not write it (the nested interface solve). 4: every load step of both runs. 5: the load-stepped run, step "
        "2 against set-up + step 1 (the set-up is counted in the first step). *Nx the bound*: the figure over the "
        "aim's bound.",
        "",
        "### Reading",
        "",
        *[paragraph + "\n" for paragraph in reading(sizes)],
        "### Every load step",
        "",
        markdown(iteration_table(sizes)),
        "",
        "* *GMRES its*: the GMRES iterations of each active-set iteration (the nested solve's interface GMRES or "
        "the coupled solve's outer GMRES), their sum and largest over the step.",
        "",
        "### Method and caveats",
        "",
        f"* {env['nproc']} cores on a machine shared with other engineers' builds and runs: wall times vary by up "
        "to 2x between runs. The runs are sequential; compare the ratios of one run of the benchmark rather "
        "than figures across reports. Load average (1 min) just before each run: " + _load_range(sizes)
        + "; on 2 cores, above ~1 means the run shared the CPU.",
        "* Each figure is one measurement (no repetition).",
        f"* A run is stopped beyond {MAX_SECONDS_OURS['direct']:.0f} s (direct) / "
        f"{MAX_SECONDS_OURS['iterative']:.0f} s (iterative, default) / {MAX_SECONDS_DOLFINX:.0f} s (dolfinx; "
        f"{MAX_SECONDS_DOLFINX_LARGE:.0f} s above 1.5M DOFs) or "
        f"{MAX_RSS_GB:.0f} GB resident and reported as skipped. The direct path is not run where its Cholesky "
        "factors are estimated not to fit (module doc of the script).",
        "* Raw numbers: `validation/build/contact_bench/results.json` (git-ignored), with the logs of every run.",
        "",
    ]
    REPORT.write_text("\n".join(text))


# ---------------------------------------------------------------------------
# Main
# ---------------------------------------------------------------------------


def _sizes_argument(value: str) -> list[str]:
    """--sizes: "small" (31k), "all", or names separated by commas."""
    names = {s.name.lower(): s.name for s in SIZES}
    if value == "small":
        return [SIZES[0].name]
    if value == "all":
        return [s.name for s in SIZES if not s.on_request]
    if value == "full":
        return [s.name for s in SIZES]
    chosen = [name.strip().lower() for name in value.split(",") if name.strip()]
    unknown = [name for name in chosen if name not in names]
    if unknown or not chosen:
        raise argparse.ArgumentTypeError(f"unknown size {', '.join(unknown) or value!r}: small, all, full or names "
                                         f"from {', '.join(names.values())}")
    return [names[name] for name in chosen]


def _paths_argument(value: str) -> list[str]:
    """--paths: names of PATHS separated by commas."""
    chosen = [name.strip() for name in value.split(",") if name.strip()]
    if not chosen or any(name not in PATHS for name in chosen):
        raise argparse.ArgumentTypeError(f"paths are {', '.join(PATHS)} (comma-separated), not {value!r}")
    return [name for name in PATHS if name in chosen]


def parse_args() -> argparse.Namespace:
    """Command line: sizes, paths, binary (and the hidden worker mode)."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=_sizes_argument, default="all",
                        help="small: the 31k-DOF mesh only (a quick check); all: 31k, 99k, 217k, 1M (default); "
                             "full: those and 3M (hours); or names, e.g. 1M, 3M or 31k,99k")
    parser.add_argument("--one-step-only", action="store_true",
                        help="leave out the load-stepped runs of ours (reported as not run)")
    parser.add_argument("--merge", action="store_true",
                        help="keep the sizes of results.json that this run does not measure (each keeps its commit, "
                             "named in the report)")
    parser.add_argument("--paths", type=_paths_argument, default="direct,iterative,default",
                        help="our paths to run, comma-separated (default: direct,iterative)")
    parser.add_argument("--binary", type=Path, default=REPO / "target/release/internodes",
                        help="internodes executable (default: target/release/internodes)")
    parser.add_argument("--report-only", action="store_true",
                        help="rewrite the report from validation/build/contact_bench/results.json without running")
    parser.add_argument("--worker", choices=("cg", "mumps"), help=argparse.SUPPRESS)
    parser.add_argument("--case", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--output", type=Path, help=argparse.SUPPRESS)
    return parser.parse_args()


def explain_not_run(size: dict) -> dict:
    """A run left out by --paths gets the reason it would not be run anyway, where there is one: the
    direct path's memory estimate, or (iterative path) the default path having run the same solvers
    at this size (CG + AMG bodies, GMRES)."""
    runs = size["runs"]
    for run in OURS:
        path = RUNS[run][1]
        if not runs[run].get("not_run", "").startswith("not selected"):
            continue
        if path == "direct" and (reason := not_run_reason(path, dofs(size))):
            runs[run] = {"not_run": reason}
        default = runs.get(run.replace(path, "default"), {})
        resolved = default.get("resolved") or {}
        if path == "iterative" and timed(default) and resolved.get("body_solver") == "cg-amg" \
                and resolved.get("solver") == "krylov":
            runs[run] = {"not_run": "the default path ran the same solvers at this size (CG + AMG bodies, GMRES on "
                                    "the interface), so its runs are the iterative path's"}
    return size


def upgrade(size: dict) -> dict:
    """A size of a results.json written before the two paths (runs ours_one / ours_steps: the default,
    Cholesky + Schur) in today's form: those are the direct runs, the iterative ones are not run."""
    runs = size["runs"]
    for old, new in (("ours_one", "direct_one"), ("ours_steps", "direct_steps")):
        if old in runs:
            run = runs.pop(old)
            if "cholesky" in run:
                run["body_setup"], run["body_setup_label"] = run.pop("cholesky"), "Cholesky"
            runs[new] = run | {"path": "direct"} if timed(run) else run
    for run in OURS:
        runs.setdefault(run, {"not_run": "not in results.json (written before the iterative path was benchmarked)"})
    runs.setdefault("dolfinx_cg_mpi", {"not_run": "not in results.json (written before the MPI run was added)"})
    for path in RANK_PATHS:  # written before the agreement: computed from the kept output folders
        for one in ("one", "steps"):
            serial_run, parallel_run = runs.get(f"default_{one}", {}), runs.get(f"{path}_{one}", {})
            folders = [BENCH / size["name"] / f"{p}_{one}" for p in ("default", path)]
            if (timed(serial_run) and timed(parallel_run) and "vs_serial" not in parallel_run
                    and all((f / "solution.h5").is_file() for f in folders)):
                parallel_run["vs_serial"] = rank_agreement(*folders)
    return size


def print_results(sizes: list[dict]) -> None:
    """The tables and the reading on stdout."""
    for table in (contact_table, comparison_table, aims_table, rank_table, iteration_table):
        print()
        print(markdown(table(sizes)))
    print()
    for paragraph in reading(sizes):
        print(paragraph, end="\n\n")


def failed(sizes: list[dict], expected: int) -> bool:
    """Whether a size is missing, a run of ours did not finish or converge, a dolfinx run failed (not stopped
    at a limit), or no dolfinx run finished at a size. A path not run is not a failure."""
    return len(sizes) < expected or any(
        any(status(s["runs"][run]) not in ("ok", "not run") for run in OURS)
        or any(status(s["runs"].get(run, {"not_run": ""})) == "failed" for run in DOLFINX)
        or best_dolfinx(s["runs"]) is None for s in sizes)


def main() -> int:
    """Environment, every size, report; exit status 1 on a failure (``failed``)."""
    args = parse_args()
    if args.worker:
        dolfinx_worker(args.worker, args.case, args.output)
        return 0

    if args.report_only:
        results = json.loads((BENCH / "results.json").read_text())
        sizes = [explain_not_run(upgrade(size)) for size in results["sizes"]]
        print_results(sizes)
        write_report(results["environment"], sizes, results["argv"])
        print(f"report: {REPORT.relative_to(REPO)}")
        return 0

    binary = args.binary.resolve()
    if not os.access(binary, os.X_OK):
        print(f"error: {binary} is not an executable (cargo build --release --features petsc)", file=sys.stderr)
        return 2
    env = environment(binary)
    print(f"machine: {env['cpu']}, {env['nproc']} cores, {env['memory_gib']} GiB")
    print(f"versions: {env['binary_version']} ({env['commit']}), {env['rustc']}, dolfinx {env['dolfinx']}, "
          f"PETSc {env['petsc']}")
    print(f"BLAS: {env['blas']}" + ("" if env["openblas"] else "  (not OpenBLAS: dolfinx's MUMPS will be slower; "
                                    "apt-get install libopenblas0-pthread)"))

    earlier = None
    if args.merge and (BENCH / "results.json").is_file():
        earlier = json.loads((BENCH / "results.json").read_text())
        if "modified" in env.get("commit", ""):
            print("error: --merge: the tree has uncommitted changes", file=sys.stderr)
            return 2
        for size in earlier["sizes"]:  # each size keeps the commit it was measured at
            size.setdefault("commit", earlier["environment"].get("commit"))
    sizes = []
    selected = [s for s in SIZES if s.name in args.sizes]
    for size in selected:
        print(f"== {size.name} DOFs (level {size.level})", flush=True)
        done = sizes + [upgrade(s) for s in (earlier or {}).get("sizes", [])]
        try:
            sizes.append(benchmark_size(size, binary, args.paths, done, args.one_step_only)
                         | {"commit": env.get("commit")})
        except (RunFailed, OSError) as error:
            print(f"   FAILED: {error}", flush=True)

    argv = [Path(sys.argv[0]).name, *sys.argv[1:]]
    if earlier:
        measured = {s["name"] for s in sizes}
        kept = [upgrade(s) for s in earlier["sizes"] if s["name"] not in measured]
        order = [s.name for s in SIZES]
        sizes = sorted(kept + sizes, key=lambda s: order.index(s["name"]))
        argv = [*earlier["argv"], "+", *argv]
        selected = [s for s in SIZES if s.name in {x["name"] for x in sizes}]
    sizes = [explain_not_run(size) for size in sizes]
    # The raw numbers first: a fault in the report's text then costs a --report-only, not the runs.
    BENCH.mkdir(parents=True, exist_ok=True)
    (BENCH / "results.json").write_text(json.dumps({"environment": env, "argv": argv, "sizes": sizes}, indent=2))
    print_results(sizes)
    write_report(env, sizes, argv)
    print(f"report: {REPORT.relative_to(REPO)}, raw numbers: {(BENCH / 'results.json').relative_to(REPO)}")
    return 1 if failed(sizes, len(selected)) else 0


if __name__ == "__main__":
    sys.exit(main())
