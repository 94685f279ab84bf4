#!/usr/bin/python3
"""Performance benchmark of internodes against FEniCSx (dolfinx 0.5.2): ``make bench``.

Problem: the single block of ``geo/block_3d.geo`` (P1 tetrahedra), clamped
base, Hertzian pressure on the top face, E = 1000, nu = 0.3 (the case
``validation/cases/block_3d.toml``), meshed at about 30k, 100k and 300k
DOFs into ``validation/build/bench/``.

For every size, each of these runs is a separate process, run one after the
other, so that its wall time and peak resident memory (``ru_maxrss`` from
``os.wait4``) are its own:

  1. ours, nested dissection  ``internodes solve CASE --quiet`` with
                               ``[solver] ordering = "nested-dissection"``;
  2. ours, AMD                the same with ``ordering = "amd"``;
  3. dolfinx, CG + GAMG       (rtol 1e-10, rigid-body near-null space);
  4. dolfinx, MUMPS Cholesky  (``preonly`` + ``cholesky``).

The dolfinx runs are this same script started with ``--worker``; they build
the model with ``dolfinx_reference.py`` from the same mesh and case file,
time form compilation, the assembly of A (``assemble_matrix`` +
``A.assemble()``) and the solve, and save their displacement in our node
numbering, which is compared with ours (relative L2 difference).

Results: a table on stdout, the report ``validation/BENCHMARK.md`` and the
raw numbers ``validation/build/bench/results.json``.

Usage:  /usr/bin/python3 validation/benchmark.py [--sizes small|all] [--binary PATH]
        /usr/bin/python3 validation/benchmark.py --report-only   (rewrite the report from results.json)

Run it with nothing else running on the machine: timings are wall times.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import re
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

VALIDATION = Path(__file__).resolve().parent
REPO = VALIDATION.parent
BENCH = VALIDATION / "build" / "bench"
REPORT = VALIDATION / "BENCHMARK.md"
BASE_CASE = VALIDATION / "cases" / "block_3d.toml"
GEO = REPO / "geo" / "block_3d.geo"
BODY = "block"
BLAS_ALTERNATIVE = Path("/etc/alternatives/libblas.so.3-x86_64-linux-gnu")
COMMAND = "make bench   # = /usr/bin/python3 validation/benchmark.py --sizes all"

# A run is killed (and reported as skipped) beyond these limits.
MAX_RSS_GB = 15.0
MAX_SECONDS = 600.0
CG_RTOL = 1e-10
# The dolfinx runs are serial: one BLAS / OpenMP thread.
SERIAL_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}


@dataclass(frozen=True)
class Size:
    """One mesh of the benchmark: ``level`` of block_3d.geo (all mesh sizes times 2^-level)."""

    name: str
    level: float

    @property
    def mesh(self) -> Path:
        return BENCH / f"block_3d_level{self.level}.msh"

    @property
    def folder(self) -> Path:
        return BENCH / self.name


# Levels chosen so that 3 x (number of nodes) is about 30k, 100k and 300k
# with gmsh 4.8 (29 469, 100 530 and 299 520 DOFs).
SIZES = (Size("30k", 1.15), Size("100k", 1.78), Size("300k", 2.33))

# name -> (label, kind, option): kind "ours" (option: ordering) or "dolfinx" (option: solver).
RUNS = {
    "ours_nd": ("ours, nested dissection", "ours", "nested-dissection"),
    "ours_amd": ("ours, AMD", "ours", "amd"),
    "dolfinx_cg": ("dolfinx, CG + GAMG", "dolfinx", "cg"),
    "dolfinx_mumps": ("dolfinx, MUMPS Cholesky", "dolfinx", "mumps"),
}


class RunFailed(RuntimeError):
    """A benchmark run failed or was stopped; the message says why."""


# ---------------------------------------------------------------------------
# Processes: wall time, CPU time and peak memory of one child
# ---------------------------------------------------------------------------


def _rss_gb(pid: int) -> float:
    """Current resident memory of a process and its descendants (GB; 0 if it is gone): under
    mpirun the ranks are mpirun's children, and the limit is on their sum."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return 0.0
    match = re.search(r"^VmRSS:\s+(\d+) kB", status, re.MULTILINE)
    own = int(match[1]) / 2**20 if match else 0.0
    try:
        children = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
    except OSError:
        children = []
    return own + sum(_rss_gb(int(child)) for child in children)


def measure(command: list, log: Path, env: dict | None = None, *, max_seconds: float = MAX_SECONDS,
            max_rss_gb: float = MAX_RSS_GB, check: bool = True) -> dict:
    """Run ``command`` (output to ``log``); its wall time, CPU time, peak RSS, exit status and
    the 1-minute load average of the machine just before it.

    The child is killed if it exceeds ``max_rss_gb`` or ``max_seconds`` (RunFailed).
    A non-zero exit status is a RunFailed too unless ``check`` is false.
    Peak RSS is the child's own ``ru_maxrss`` from ``os.wait4``.
    """
    load = os.getloadavg()[0]  # other processes on the machine (shared): reported with the run
    with open(log, "w") as out:
        start = time.perf_counter()
        # Its own process group: a kill takes mpirun's ranks too.
        child = subprocess.Popen([str(c) for c in command], stdout=out, stderr=subprocess.STDOUT,
                                 env=os.environ | (env or {}), start_new_session=True)
        stopped = None
        while True:
            pid, status, usage = os.wait4(child.pid, os.WNOHANG)
            if pid:
                break
            elapsed, rss = time.perf_counter() - start, _rss_gb(child.pid)
            if stopped is None and (elapsed > max_seconds or rss > max_rss_gb):
                stopped = (f"stopped after {elapsed:.0f} s at {rss:.1f} GB "
                           f"(limits {max_seconds:.0f} s, {max_rss_gb:.0f} GB)")
                os.killpg(child.pid, signal.SIGKILL)
            time.sleep(0.05)
        wall = time.perf_counter() - start
    child.returncode = os.waitstatus_to_exitcode(status)
    if stopped:
        raise RunFailed(stopped)
    if check and child.returncode != 0:
        tail = " | ".join(log.read_text().strip().splitlines()[-3:])
        raise RunFailed(f"exit status {child.returncode}: {tail}")
    return {"wall": wall, "cpu": usage.ru_utime + usage.ru_stime, "peak_mb": usage.ru_maxrss / 1024,
            "load_before": load, "exit_status": child.returncode}


# ---------------------------------------------------------------------------
# Step 1: meshes and case files
# ---------------------------------------------------------------------------


def mesh_nodes(mesh: Path) -> int:
    """Number of nodes of an MSH 4.1 file (the line after ``$Nodes``)."""
    with open(mesh) as f:
        for line in f:
            if line.strip() == "$Nodes":
                return int(next(f).split()[1])
    raise RunFailed(f"{mesh}: no $Nodes section")


def generate_mesh(size: Size) -> None:
    """gmsh -3 geo/block_3d.geo -setnumber level L (kept if it already exists)."""
    if size.mesh.is_file():
        return
    size.mesh.parent.mkdir(parents=True, exist_ok=True)
    result = subprocess.run(["gmsh", "-3", str(GEO), "-setnumber", "level", str(size.level),
                             "-format", "msh41", "-o", str(size.mesh), "-v", "1"], capture_output=True, text=True)
    if result.returncode != 0:
        raise RunFailed(f"gmsh level {size.level}: {result.stdout[-500:]}{result.stderr[-500:]}")


def write_cases(size: Size) -> dict[str, Path]:
    """The case file for this mesh (dolfinx: "base") and one per ordering of ours.

    The base case is validation/cases/block_3d.toml with ``mesh`` replaced;
    ours add a ``[solver]`` table with the ordering, and ``body = "cholesky"``: this benchmark times
    the sparse Cholesky path (``auto`` would take CG + AMG for the larger 3D meshes in a PETSc
    build; ``validation/body_solver_benchmark.py`` compares the two).
    """
    size.folder.mkdir(parents=True, exist_ok=True)
    text, count = re.subn(r"(?m)^mesh\s*=.*$", f"mesh = {json.dumps(str(size.mesh))}", BASE_CASE.read_text())
    if count != 1:
        raise RunFailed(f"{BASE_CASE}: expected one top-level 'mesh = ...' line, found {count}")
    cases = {"base": size.folder / "block_3d.toml"}
    cases["base"].write_text(text)
    for run, (_, kind, ordering) in RUNS.items():
        if kind == "ours":
            cases[run] = size.folder / f"block_3d_{run}.toml"
            cases[run].write_text(f'{text}\n[solver]\nbody = "cholesky"\nordering = "{ordering}"\n')
    return cases


# ---------------------------------------------------------------------------
# Step 2: the runs
# ---------------------------------------------------------------------------


def run_ours(binary: Path, case: Path, output: Path) -> dict:
    """One internodes solve; phases from summary.json, displacement from solution.h5."""
    import h5py

    shutil.rmtree(output, ignore_errors=True)  # never read a stale summary
    usage = measure([binary, "solve", case, "--quiet", "--output", output], output.with_suffix(".log"))
    summary = json.loads((output / "summary.json").read_text())
    (body,) = [b for b in summary["bodies"] if b["name"] == BODY]
    phases = dict(body["solve"]["timings"])
    with h5py.File(output / "solution.h5", "r") as f:
        np.save(output.with_suffix(".u.npy"), f["/fields/displacement"][:])
    return usage | {
        "dofs": body["num_dofs"],
        "stiffness_nnz": body["solve"]["stiffness_nnz"],
        "factor_nnz": body["solve"]["factor_nnz"],
        "relative_residual": body["solve"]["relative_residual"],
        "phases": phases,
        "internal_timings": dict(summary["timings"]),
        "read_mesh": sum(t for phase, t in summary["timings"] if "mesh" in phase),
        "assemble": phases["sparsity pattern"] + phases["assemble stiffness"],
        "ordering": phases["ordering + symbolic"],
        "factor": phases["numeric factorization"],
        "solve": phases["triangular solves"],
    }


def run_dolfinx(solver: str, cases: dict[str, Path], coordinates: Path, output: Path) -> dict:
    """One dolfinx run (this script with --worker) in a serial environment."""
    result = output.with_suffix(".json")
    usage = measure([sys.executable, __file__, "--worker", solver, "--case", cases["base"],
                     "--coordinates", coordinates, "--output", result],
                    output.with_suffix(".log"), env=SERIAL_ENV)
    return usage | json.loads(result.read_text())


def relative_l2(u: np.ndarray, reference: np.ndarray) -> float:
    """||u - reference||_2 / ||reference||_2."""
    return float(np.linalg.norm(u - reference) / np.linalg.norm(reference))


def benchmark_size(size: Size, binary: Path) -> dict:
    """Mesh, the four runs one after the other, and the displacement differences."""
    generate_mesh(size)
    cases = write_cases(size)
    runs: dict[str, dict] = {}
    for run, (label, kind, option) in RUNS.items():
        print(f"   {label} ...", end=" ", flush=True)
        output = size.folder / run
        try:
            if kind == "ours":
                runs[run] = run_ours(binary, cases[run], output)
            else:
                if status(runs["ours_nd"]) != "ok":
                    raise RunFailed("needs the node coordinates of the nested-dissection run")
                runs[run] = run_dolfinx(option, cases, size.folder / "ours_nd" / "solution.h5", output)
            print(f"{runs[run]['wall']:.1f} s, {runs[run]['peak_mb']:.0f} MB", flush=True)
        except (RunFailed, OSError, KeyError, ValueError) as error:
            runs[run] = {"error": f"{type(error).__name__}: {error}"}
            print(f"FAILED ({runs[run]['error']})", flush=True)
    compare_displacements(size, runs)
    return {"name": size.name, "level": size.level, "mesh": str(size.mesh.relative_to(REPO)),
            "nodes": mesh_nodes(size.mesh), "runs": runs}


def compare_displacements(size: Size, runs: dict[str, dict]) -> None:
    """runs[r]["l2_vs"]: relative L2 difference with ours (ND) for dolfinx, with MUMPS for ours."""
    u = {run: np.load(size.folder / f"{run}.u.npy") for run in runs if "error" not in runs[run]}
    for run in u:
        reference = "dolfinx_mumps" if RUNS[run][1] == "ours" else "ours_nd"
        if reference in u and reference != run:
            runs[run]["l2_vs"] = {"reference": reference, "value": relative_l2(u[run], u[reference])}


# ---------------------------------------------------------------------------
# The dolfinx worker (a separate process per run)
# ---------------------------------------------------------------------------


def dolfinx_worker(solver: str, case: Path, coordinates: Path, output: Path) -> None:
    """Build, assemble and solve with dolfinx; timings and results to ``output`` (JSON, .u.npy)."""
    import h5py
    from dolfinx import fem
    from petsc4py import PETSc

    from dolfinx_reference import ReferenceModel, read_case

    timings = {}
    clock = time.perf_counter()

    def lap(phase: str) -> None:
        """Time since the previous lap, stored under ``phase``."""
        nonlocal clock
        timings[phase] = time.perf_counter() - clock
        clock = time.perf_counter()

    # a. Mesh (gmsh -> dolfinx) and the body of the case file.
    case = read_case(case)
    (body,) = case.bodies
    with h5py.File(coordinates, "r") as f:
        ours = f["/mesh/geometry"][:]
    model = ReferenceModel(case.mesh, {body.name: ours})
    lap("mesh")
    # b. Form compilation (FFCx JIT, cached across runs: varies).
    a, L = fem.form(model.stiffness_form(body)), fem.form(model.load_form(body))
    lap("form compilation")
    # c. Dirichlet conditions (every component fixed on each group).
    bcs = []
    for d in body.dirichlet:
        if any(v is None for v in d.values):
            raise RunFailed("the benchmark expects fully clamped Dirichlet groups")
        dofs = fem.locate_dofs_topological(model.V, model.dim - 1, model.facets(d.group))
        bcs.append(fem.dirichletbc(np.array(d.values, dtype=PETSc.ScalarType), dofs, model.V))
    lap("boundary conditions")
    A, b, x, ksp, r = assemble_and_solve(solver, a, L, bcs, model, lap)
    result = {"timings": timings, "assemble": timings["assemble"], "compile": timings["form compilation"],
              "solver_total": timings["setup"] + timings["solve"], "iterations": ksp.getIterationNumber(),
              "relative_residual": r.norm() / b.norm(), "matrix_nnz": int(A.getInfo()["nz_used"]),
              "dofs": A.getSize()[0]}
    if solver == "mumps":
        factor = ksp.getPC().getFactorMatrix()
        ordering = {0: "AMD", 2: "AMF", 3: "SCOTCH", 4: "PORD", 5: "METIS", 6: "QAMD"}
        result["mumps_ordering"] = ordering.get(factor.getMumpsInfog(7), str(factor.getMumpsInfog(7)))
        result["factor_nnz"] = int(factor.getMumpsInfog(29))  # entries in the factors (L, symmetric)
    np.save(output.with_suffix(".u.npy"), x.array[model.dof_map(body.name)].reshape(-1, model.dim))
    output.write_text(json.dumps(result, indent=2))


def assemble_and_solve(solver: str, a, L, bcs: list, model, lap):
    """Assembly of A and b, then the PETSc solve, each phase timed by ``lap``; returns
    ``(A, b, x, ksp, r)`` with ``r = A x - b`` (raises RunFailed if the KSP did not converge)."""
    from dolfinx.fem import petsc
    from petsc4py import PETSc

    # d. Assembly of A (sparsity pattern, matrix, constrained rows / columns), then the
    #    right-hand side (lifting of the prescribed displacements).
    A = petsc.assemble_matrix(a, bcs=bcs)
    A.assemble()
    lap("assemble")
    b = petsc.assemble_vector(L)
    petsc.apply_lifting(b, [a], [bcs])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    petsc.set_bc(b, bcs)
    lap("assemble loads")
    # e. Solve: setup (GAMG hierarchy / MUMPS analysis + factorization), then solve.
    ksp = _krylov_solver(solver, A, model)
    lap("solver creation")
    ksp.setUp()
    lap("setup")
    x = A.createVecRight()
    ksp.solve(b, x)
    lap("solve")
    if ksp.getConvergedReason() <= 0:
        raise RunFailed(f"{solver}: KSP did not converge (reason {ksp.getConvergedReason()})")
    r = b.duplicate()
    A.mult(x, r)
    r.axpy(-1.0, b)
    return A, b, x, ksp, r


def _krylov_solver(solver: str, A, model):
    """PETSc KSP: "cg" (CG + GAMG with the rigid-body near-null space, rtol CG_RTOL) or "mumps"."""
    from petsc4py import PETSc

    from dolfinx_reference import rigid_body_modes

    ksp = PETSc.KSP().create(A.getComm())
    ksp.setOperators(A)
    if solver == "cg":
        modes, _ = np.linalg.qr(rigid_body_modes(model.V.tabulate_dof_coordinates()[:, : model.dim]))
        vectors = [A.createVecLeft() for _ in range(modes.shape[1])]
        for vector, mode in zip(vectors, modes.T):
            vector.array[:] = mode
        A.setNearNullSpace(PETSc.NullSpace().create(vectors=vectors))
        ksp.setType("cg")
        ksp.setTolerances(rtol=CG_RTOL, atol=0.0, max_it=10000)
        ksp.getPC().setType("gamg")
    else:
        A.setOption(PETSc.Mat.Option.SPD, True)
        ksp.setType("preonly")
        ksp.getPC().setType("cholesky")
        ksp.getPC().setFactorSolverType("mumps")
    ksp.setFromOptions()  # PETSC_OPTIONS may add e.g. -ksp_view, -log_view
    return ksp


# ---------------------------------------------------------------------------
# Step 0 and 3: environment, table, report
# ---------------------------------------------------------------------------


def environment(binary: Path) -> dict:
    """Machine, versions and BLAS (printed and written to the report)."""
    from petsc4py import PETSc

    import dolfinx

    def output(command: list) -> str:
        try:
            result = subprocess.run(command, capture_output=True, text=True, cwd=REPO)
            return (result.stdout or result.stderr).strip()
        except OSError:
            return "unavailable"

    cpu = re.search(r"^model name\s*:\s*(.*)$", Path("/proc/cpuinfo").read_text(), re.MULTILINE)
    memory = re.search(r"^MemTotal:\s+(\d+) kB", Path("/proc/meminfo").read_text(), re.MULTILINE)
    blas = os.path.realpath(BLAS_ALTERNATIVE) if BLAS_ALTERNATIVE.exists() else "unknown"
    commit = output(["git", "rev-parse", "--short", "HEAD"])
    dirty = " (working tree modified)" if output(["git", "status", "--porcelain", "--", "src", "Cargo.toml"]) else ""
    return {
        "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
        "cpu": cpu[1] if cpu else "unknown", "nproc": os.cpu_count(),
        "memory_gib": round(int(memory[1]) / 2**20, 1) if memory else None,
        "os": output(["sh", "-c", ". /etc/os-release && echo $PRETTY_NAME"]) or platform.platform(),
        "rustc": output(["rustc", "--version"]), "binary": str(binary),
        "binary_version": output([binary, "--version"]), "commit": commit + dirty,
        "dolfinx": dolfinx.__version__, "petsc": ".".join(map(str, PETSc.Sys.getVersion())),
        "blas": blas, "openblas": "openblas" in blas, "gmsh": output(["gmsh", "--version"]) or "unknown",
    }


def fmt(value, digits: int = 3) -> str:
    """A figure with ``digits`` significant digits ("-" if missing)."""
    if value is None:
        return "-"
    return f"{value:.{digits}g}" if abs(value) < 10**digits else f"{value:.0f}"


def status(run: dict) -> str:
    """"ok", "skipped" (stopped at the time / memory limit) or "failed"."""
    if "error" not in run:
        return "ok"
    return "skipped" if "stopped after" in run["error"] else "failed"


def best_ours(runs: dict) -> str | None:
    """The faster of our two runs (assembly + ordering + factorization + solve)."""
    done = [r for r in ("ours_nd", "ours_amd") if "error" not in runs.get(r, {"error": ""})]
    return min(done, key=lambda r: our_solve_total(runs[r]), default=None)


def best_dolfinx(runs: dict) -> str | None:
    """The faster dolfinx solver (setup + solve)."""
    done = [r for r in ("dolfinx_cg", "dolfinx_mumps") if "error" not in runs.get(r, {"error": ""})]
    return min(done, key=lambda r: runs[r]["solver_total"], default=None)


def our_solve_total(run: dict) -> float:
    """Assembly + ordering and symbolic + numeric factorization + triangular solves."""
    return run["assemble"] + run["ordering"] + run["factor"] + run["solve"]


def ratios(runs: dict) -> tuple[float | None, float | None]:
    """(our assembly / dolfinx assembly, our best solve total / dolfinx best solve total).

    Each code's assembly time is the minimum over its runs (every run assembles).
    """
    ours, theirs = best_ours(runs), best_dolfinx(runs)
    if ours is None or theirs is None:
        return None, None
    assemble_ours = min(runs[r]["assemble"] for r in ("ours_nd", "ours_amd") if "error" not in runs[r])
    assemble_theirs = min(runs[r]["assemble"] for r in ("dolfinx_cg", "dolfinx_mumps") if "error" not in runs[r])
    total_theirs = assemble_theirs + runs[theirs]["solver_total"]
    return assemble_ours / assemble_theirs, our_solve_total(runs[ours]) / total_theirs


def summary_table(sizes: list[dict]) -> list[list[str]]:
    """The main table: one row per size."""
    header = ["DOFs", "nnz(K)",
              "ND asm", "ND fact", "ND solve", "ND total", "ND MB",
              "AMD asm", "AMD fact", "AMD solve", "AMD total", "AMD MB",
              "dfx asm", "dfx CG+GAMG (its)", "dfx MUMPS", "dfx MB",
              "asm ratio", "solve ratio", "Δu MUMPS", "Δu CG"]
    rows = [header]
    for size in sizes:
        runs, row = size["runs"], []
        nd = runs["ours_nd"]
        row += [f"{3 * size['nodes']:,}", f"{nd['stiffness_nnz']:,}" if "error" not in nd else "-"]
        for run in ("ours_nd", "ours_amd"):
            r = runs[run]
            row += ([status(r)] + ["-"] * 4 if "error" in r else
                    [fmt(r["assemble"]), fmt(r["ordering"] + r["factor"]), fmt(r["solve"]), fmt(r["wall"]),
                     f"{r['peak_mb']:.0f}"])
        cg, mumps = runs["dolfinx_cg"], runs["dolfinx_mumps"]
        assembly = [r["assemble"] for r in (cg, mumps) if "error" not in r]
        row += [fmt(min(assembly)) if assembly else "-",
                f"{fmt(cg['solver_total'])} ({cg['iterations']})" if "error" not in cg else status(cg),
                fmt(mumps["solver_total"]) if "error" not in mumps else status(mumps),
                " / ".join(f"{r['peak_mb']:.0f}" for r in (cg, mumps) if "error" not in r) or "-"]
        assembly_ratio, solve_ratio = ratios(runs)
        row += [fmt(assembly_ratio, 2), fmt(solve_ratio, 2)]
        row += [f"{r['l2_vs']['value']:.1e}" if "l2_vs" in r else "-" for r in (mumps, cg)]
        rows.append(row)
    return rows


def detail_table(sizes: list[dict]) -> list[list[str]]:
    """Every run: all its phases, wall / CPU time, peak memory, factor size, residual, Δu."""
    rows = [["DOFs", "run", "read mesh", "compile", "assemble", "ordering + symbolic", "factor / setup",
             "solve", "wall", "CPU / wall", "peak MB", "nnz(L)", "residual", "Δu (vs)"]]
    for size in sizes:
        for run, (label, kind, option) in RUNS.items():
            r = size["runs"][run]
            if "error" in r:
                rows.append([f"{3 * size['nodes']:,}", label, r["error"]] + [""] * 11)
                continue
            if kind == "ours":
                phases = [r["read_mesh"], None, r["assemble"], r["ordering"], r["factor"], r["solve"]]
            else:
                t = r["timings"]
                phases = [t["mesh"], t["form compilation"], r["assemble"], None, t["setup"], t["solve"]]
                label += f" ({r['iterations']} its)" if option == "cg" else f" ({r['mumps_ordering']})"
            l2 = r.get("l2_vs")
            rows.append([f"{3 * size['nodes']:,}", label, *map(fmt, phases), fmt(r["wall"]),
                         f"{r['cpu'] / r['wall']:.2f}", f"{r['peak_mb']:.0f}",
                         f"{r['factor_nnz']:,}" if "factor_nnz" in r else "-", f"{r['relative_residual']:.1e}",
                         f"{l2['value']:.1e} ({RUNS[l2['reference']][0]})" if l2 else "-"])
    return rows


def markdown(rows: list[list[str]]) -> str:
    """A pipe table, columns padded (readable on a terminal too)."""
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    lines = ["| " + " | ".join(cell.ljust(w) for cell, w in zip(row, widths)) + " |" for row in rows]
    lines.insert(1, "|" + "|".join("-" * (w + 2) for w in widths) + "|")
    return "\n".join(lines)


def _done(size: dict, *runs: str) -> bool:
    """Whether all these runs of a size completed."""
    return all(status(size["runs"][r]) == "ok" for r in runs)


def _series(values: list[float], unit: str = "x") -> str:
    """"1.2x, 1.5x" (one figure per size)."""
    return ", ".join(f"{v:.2f}{unit}" for v in values)


def _trend(values: list[float]) -> str:
    """" (growing with the size)" / " (shrinking ...)" when monotonic over several sizes."""
    if len(values) < 2:
        return ""
    pairs = list(zip(values, values[1:]))
    if all(b > a for a, b in pairs):
        return " (growing with the size)"
    if all(b < a for a, b in pairs):
        return " (shrinking with the size)"
    return ""


def reading(sizes: list[dict]) -> list[str]:
    """A short reading of the figures, derived from them (one paragraph per point)."""
    text = []
    # Ordering: AMD against nested dissection.
    both = [s for s in sizes if _done(s, "ours_nd", "ours_amd")]
    if both:
        nd, amd = [s["runs"]["ours_nd"] for s in both], [s["runs"]["ours_amd"] for s in both]
        work = [(a["ordering"] + a["factor"]) / (n["ordering"] + n["factor"]) for n, a in zip(nd, amd)]
        winner = "Nested dissection" if min(work) > 1 else ("AMD" if max(work) < 1 else "Neither ordering")
        text.append(
            f"**Ordering.** {winner} wins. At {', '.join(s['name'] for s in both)} DOFs, AMD's ordering + "
            f"factorization takes {_series(work)} the time of nested dissection's{_trend(work)}, with "
            f"{_series([a['factor_nnz'] / n['factor_nnz'] for n, a in zip(nd, amd)])} its factor entries and "
            f"{_series([a['peak_mb'] / n['peak_mb'] for n, a in zip(nd, amd)])} its peak memory. "
            "Nested dissection is the right default for 3D meshes.")
    for s in sizes:
        if status(s["runs"]["ours_amd"]) != "ok":
            text.append(f"AMD at {s['name']} DOFs: {s['runs']['ours_amd']['error']}.")
    # Assembly.
    measured = [(s["name"], ratios(s["runs"])[0]) for s in sizes if ratios(s["runs"])[0] is not None]
    if measured:
        missed = [name for name, r in measured if r > 1.0]
        text.append(
            f"**Assembly.** Our assembly (sparsity pattern + stiffness) takes {_series([r for _, r in measured])} "
            f"the time of dolfinx's `assemble_matrix` + `A.assemble()` (its sparsity pattern, assembly and "
            f"Dirichlet rows) on the same mesh at {', '.join(n for n, _ in measured)} DOFs: the aim \"at least as "
            "fast as dolfinx's\" is " + (f"missed at {', '.join(missed)} DOFs." if missed else "met at every size.")
            + (" A miss by less than 15% is within the run-to-run variation of this shared machine (a repeat "
               "can flip it): read it as parity." if missed and max(r for _, r in measured) < 1.15 else "")
            + " Applying our Dirichlet conditions is a separate phase, not counted (see *Every run*: "
            "`summary.json`, \"apply Dirichlet conditions\").")
    # Solve: against the best dolfinx solver, and what bounds our time.
    compared = [s for s in sizes if None not in ratios(s["runs"])]
    if compared:
        parts = []
        for s in compared:
            ours = s["runs"][best_ours(s["runs"])]
            parts.append(f"{ratios(s['runs'])[1]:.2f}x at {s['name']} against {RUNS[best_dolfinx(s['runs'])][0]}, "
                         f"numeric factorization {ours['factor'] / our_solve_total(ours):.0%} of our time")
        text.append("**Solve.** Our assembly + ordering + factorization + solve against dolfinx's assembly + "
                    "best solver: " + "; ".join(parts) + ".")
    with_cg = [s for s in compared if _done(s, "dolfinx_cg")]
    if with_cg:
        against_cg = [our_solve_total(s["runs"][best_ours(s["runs"])])
                      / (s["runs"]["dolfinx_cg"]["assemble"] + s["runs"]["dolfinx_cg"]["solver_total"])
                      for s in with_cg]
        iterations = [s["runs"]["dolfinx_cg"]["iterations"] for s in with_cg]
        memory = [s["runs"][best_ours(s["runs"])]["peak_mb"] / s["runs"]["dolfinx_cg"]["peak_mb"] for s in with_cg]
        text.append(
            f"Against CG + GAMG alone the time ratio is {_series(against_cg)}{_trend(against_cg)}, with "
            f"{', '.join(map(str, iterations))} CG iterations, and the peak-memory ratio {_series(memory)}. This is the expected limit of a sparse direct "
            "solver in 3D: with nested dissection the factor grows like n^(4/3) and the factorization work like "
            "n^2, while CG + GAMG costs about O(n) per iteration with a nearly constant iteration count. Where we "
            "are slower, the bound is the numeric factorization (its flop count, fixed by the ordering, and the "
            "kernel's flop rate), not assembly.")
    # Against MUMPS, the other direct solver.
    direct = [s for s in sizes if _done(s, "ours_nd", "dolfinx_mumps")]
    if direct:
        nd, mumps = [s["runs"]["ours_nd"] for s in direct], [s["runs"]["dolfinx_mumps"] for s in direct]
        fill = [n["factor_nnz"] / m["factor_nnz"] for n, m in zip(nd, mumps)]
        text.append(
            f"**Against MUMPS** (Cholesky, ordering {mumps[0]['mumps_ordering']}): our nested-dissection factor "
            f"has {_series(fill)} MUMPS's entries, and "
            f"our ordering + factorization + solve takes "
            f"{_series([(n['ordering'] + n['factor'] + n['solve']) / m['solver_total'] for n, m in zip(nd, mumps)])}"
            f" the time of MUMPS's analysis + factorization + solve, with "
            f"{_series([n['peak_mb'] / m['peak_mb'] for n, m in zip(nd, mumps)])} its peak memory. "
            + ("With about the same fill, the time gap is the speed of the factorization kernels (MUMPS with "
               "one BLAS thread, BLAS library in the table above)."
               if all(0.8 < f < 1.25 for f in fill) else "The fills differ: the orderings matter as much as "
               "the kernels."))
    cores = [s["runs"]["ours_nd"]["cpu"] / s["runs"]["ours_nd"]["wall"] for s in sizes if _done(s, "ours_nd")]
    if cores:
        text.append(
            f"**Threads.** Our process used {_series(cores, '')} CPU seconds per wall second (nested dissection)"
            + (": in effect one core, although the binary may use rayon / faer threads; the comparison with the serial dolfinx runs is then serial against serial. "
               "Either the factorization does not run in parallel or the second core was taken by other "
               "processes (see the load averages below)." if max(cores) < 1.2 else
               ": it runs on several threads, whereas the dolfinx runs are serial (one MPI process, one BLAS "
               "thread); the time ratios above favour us by up to that factor."))
    # Sanity.
    diffs = {r: [s["runs"][r]["l2_vs"]["value"] for s in sizes if "l2_vs" in s["runs"][r]]
             for r in ("dolfinx_mumps", "dolfinx_cg")}
    if any(diffs.values()):
        text.append("**Sanity.** Relative L2 difference between our displacement and dolfinx's: at most "
                    + " and ".join(f"{max(v):.1e} against {RUNS[r][0]}" for r, v in diffs.items() if v)
                    + f" (MUMPS: round-off; CG: its rtol {CG_RTOL:.0e}).")
    return text


def _load_range(sizes: list[dict]) -> str:
    """"min to max" of the load averages measured before the runs."""
    loads = [r["load_before"] for s in sizes for r in s["runs"].values() if "load_before" in r]
    return f"{min(loads):.1f} to {max(loads):.1f}" if loads else "not measured"


def _disturbed(sizes: list[dict]) -> str:
    """The runs that got clearly less than one core (CPU / wall < 0.85): their times are overestimated."""
    runs = [f"{RUNS[name][0]} at {s['name']} ({r['cpu'] / r['wall']:.2f})" for s in sizes
            for name, r in s["runs"].items() if "cpu" in r and r["cpu"] / r["wall"] < 0.85]
    if not runs:
        return "Every run had at least 0.85 CPU seconds per wall second."
    return "Runs that had less than 0.85 CPU seconds per wall second, so their times are overestimated: " + \
        ", ".join(runs) + "."


def write_report(env: dict, sizes: list[dict], argv: list[str]) -> None:
    """validation/BENCHMARK.md: machine, versions, tables, reading, method."""
    env_rows = [["item", "value"], ["date", env["date"]], ["machine", f"{env['cpu']}, {env['nproc']} cores, "
                f"{env['memory_gib']} GiB, {env['os']}"],
                ["internodes", f"{env['binary_version']} (commit {env['commit']}), built with {env['rustc']}"],
                ["dolfinx / PETSc", f"{env['dolfinx']} / {env['petsc']}"], ["BLAS", env["blas"]],
                ["gmsh", env["gmsh"]], ["command", f"`{COMMAND}` (this run: `{' '.join(argv)}`)"]]
    text = [
        "# Performance benchmark: internodes against dolfinx",
        "",
        "Written by `validation/benchmark.py`; do not edit by hand. Regenerate with",
        "",
        "```sh",
        COMMAND,
        "```",
        "",
        markdown(env_rows),
        "",
        "**Problem.** `geo/block_3d.geo` (block [-2,2]^2 x [-2,0], mesh refined towards the origin), P1 "
        "tetrahedra, E = 1000, nu = 0.3, clamped base, Hertzian pressure p0 = 10, a = 0.2 on the top face "
        "(`validation/cases/block_3d.toml`). Mesh levels "
        + ", ".join(f"{s['level']} ({3 * s['nodes']:,} DOFs)" for s in sizes) + ".",
        "",
        "## Results",
        "",
        "Times in seconds (wall), memory in MB (peak resident set of the run's process).",
        "",
        markdown(summary_table(sizes)),
        "",
        "* **ours** (`internodes solve --quiet`): *asm* = sparsity pattern + stiffness assembly, *fact* = "
        "ordering + symbolic + numeric factorization, *solve* = triangular solves, *total* = wall time of the "
        "whole process (also mesh reading, loads, Dirichlet conditions, stresses, HDF5 output).",
        "* **dfx** (dolfinx, serial, one BLAS thread): *asm* = `assemble_matrix(a, bcs)` + `A.assemble()` after "
        "form compilation (the smaller of its two runs); *CG+GAMG* = KSP setup + solve, rtol "
        f"{CG_RTOL:.0e}, rigid-body near-null space (iterations); *MUMPS* = Cholesky analysis + factorization "
        "+ solve; *MB* = CG run / MUMPS run (includes the Python interpreter, dolfinx and the gmsh model).",
        "* *asm ratio* = our assembly / dolfinx assembly (smaller of each code's runs); *solve ratio* = our "
        "best ordering's asm + fact + solve / (dolfinx asm + its best solver); below 1: we are faster.",
        "* *Δu* = ||u_ours - u_dolfinx|| / ||u_dolfinx|| (nested dissection, nodes matched by coordinates).",
        "",
        "## Reading",
        "",
        *[paragraph + "\n" for paragraph in reading(sizes)],
        "## Every run",
        "",
        markdown(detail_table(sizes)),
        "",
        "For ours: *read mesh* = reading the .msh file; *ordering + symbolic*, *factor* (numeric), *solve* "
        "(triangular solves) as reported in `summary.json`. For dolfinx: *read mesh* = gmsh file -> dolfinx "
        "mesh (`model_to_mesh`), *compile* = FFCx form compilation (JIT-cached after the first run: varies), "
        "*setup* = `ksp.setUp()`: GAMG hierarchy, or MUMPS analysis (ordering) + factorization; the MUMPS "
        "ordering is MUMPS's automatic choice (this Debian build has no METIS / SCOTCH: asking for them "
        "falls back to PORD). The KSP is configured in code, then `setFromOptions()` (PETSc's GAMG defaults "
        "are only complete after it: without it GAMG's setup was 5x slower). *CPU / wall* = (user + "
        "system CPU time) / wall time of the process: above 1 means several threads (ours uses rayon / faer "
        "threads, dolfinx runs are serial). *nnz(L)*: factor entries (MUMPS: INFOG(29)). *residual*: "
        "||K u - f|| / ||f|| of the constrained system.",
        "",
        "## Method and caveats",
        "",
        f"* {env['nproc']} cores on a shared machine: wall times vary by up to 2x between runs. The runs are "
        "sequential (one process at a time) with nothing else of the benchmark running; compare figures of "
        "one run of the benchmark rather than across reports.",
        "* Load average (1 min) of the machine just before each run: "
        + _load_range(sizes) + "; on 2 cores, a load above ~1 before a serial run means it shared the CPU "
        "with other processes (its *CPU / wall* below 1 shows the same). " + _disturbed(sizes),
        "* Each figure is one measurement (no repetition); the smallest size is the least reliable.",
        f"* A run is stopped beyond {MAX_SECONDS:.0f} s or {MAX_RSS_GB:.0f} GB resident and reported as skipped.",
        "* Raw numbers: `validation/build/bench/results.json` (git-ignored), with the logs of every run.",
        "",
    ]
    REPORT.write_text("\n".join(text))


# ---------------------------------------------------------------------------
# Main
# ---------------------------------------------------------------------------


def parse_args() -> argparse.Namespace:
    """Command line: sizes, binary (and the hidden worker mode)."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", choices=("small", "all"), default="all",
                        help="small: the 30k-DOF mesh only (a quick check); all: 30k, 100k, 300k (default)")
    parser.add_argument("--binary", type=Path, default=REPO / "target/release/internodes",
                        help="internodes executable (default: target/release/internodes)")
    parser.add_argument("--report-only", action="store_true",
                        help="rewrite the report from validation/build/bench/results.json without running")
    parser.add_argument("--worker", choices=("cg", "mumps"), help=argparse.SUPPRESS)
    parser.add_argument("--case", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--coordinates", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--output", type=Path, help=argparse.SUPPRESS)
    return parser.parse_args()


def main() -> int:
    """Steps 0-3; exit status 1 if any run failed."""
    args = parse_args()
    if args.worker:
        dolfinx_worker(args.worker, args.case, args.coordinates, args.output)
        return 0

    if args.report_only:
        results = json.loads((BENCH / "results.json").read_text())
        write_report(results["environment"], results["sizes"], results["argv"])
        print(f"report: {REPORT.relative_to(REPO)}")
        return 0

    # 0. Environment: the binary must run; BLAS is reported (OpenBLAS or not).
    binary = args.binary.resolve()
    if not os.access(binary, os.X_OK):
        print(f"error: {binary} is not an executable (cargo build --release)", file=sys.stderr)
        return 2
    env = environment(binary)
    print(f"machine: {env['cpu']}, {env['nproc']} cores, {env['memory_gib']} GiB")
    print(f"versions: {env['binary_version']} ({env['commit']}), {env['rustc']}, dolfinx {env['dolfinx']}, "
          f"PETSc {env['petsc']}")
    print(f"BLAS: {env['blas']}" + ("" if env["openblas"] else "  (not OpenBLAS: dolfinx's MUMPS will be slower; "
                                    "apt-get install libopenblas0-pthread)"))

    # 1-2. Every size: mesh, then the four runs one after the other.
    sizes = []
    for size in SIZES[:1] if args.sizes == "small" else SIZES:
        print(f"== {size.name} DOFs (level {size.level})", flush=True)
        try:
            sizes.append(benchmark_size(size, binary))
        except (RunFailed, OSError) as error:
            print(f"   FAILED: {error}", flush=True)

    # 3. Table, report, raw numbers.
    print()
    print(markdown(summary_table(sizes)))
    print()
    for paragraph in reading(sizes):
        print(paragraph, end="\n\n")
    BENCH.mkdir(parents=True, exist_ok=True)
    argv = [Path(sys.argv[0]).name, *sys.argv[1:]]
    (BENCH / "results.json").write_text(json.dumps({"environment": env, "argv": argv, "sizes": sizes}, indent=2))
    write_report(env, sizes, argv)
    print(f"report: {REPORT.relative_to(REPO)}, raw numbers: {(BENCH / 'results.json').relative_to(REPO)}")
    failed = len(sizes) < (1 if args.sizes == "small" else len(SIZES)) or any(
        status(r) == "failed" for s in sizes for r in s["runs"].values())
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
