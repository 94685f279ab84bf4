#!/usr/bin/python3
"""The body solvers side by side: our sparse Cholesky, our CG + AMG (PETSc, cargo feature
``petsc``) and dolfinx's CG + GAMG, on 3D meshes of about 30k, 100k, 200k and 670k DOFs.

Problem: the single block of ``geo/block_3d.geo`` (the case of ``validation/benchmark.py``:
``validation/cases/block_3d.toml``, clamped base, Hertzian pressure), meshed into
``validation/build/bench/``. Every run is its own process, one after the other; wall time and
peak resident memory come from ``benchmark.measure`` (``os.wait4``):

  1. ours, Cholesky  ``internodes solve CASE --quiet`` with ``[solver] body = "cholesky"``;
  2. ours, CG + AMG  the same with ``body = "cg-amg"`` (rtol 1e-10 on ||f - K u|| / ||f||);
  3. dolfinx, CG + GAMG  ``benchmark.py --worker cg`` (rtol 1e-10 on the preconditioned
     residual, rigid-body near-null space).

A run beyond ``benchmark.MAX_SECONDS`` (600 s) or ``benchmark.MAX_RSS_GB`` (15 GB) is
stopped and reported as skipped.

Writes ``validation/BODY_SOLVER_BENCHMARK.md`` (only from a clean committed tree, whose
commit it states: ``--allow-dirty`` to try it out) and prints the table.

Usage:  /usr/bin/python3 validation/body_solver_benchmark.py [--sizes 30k,100k,...] [--binary PATH]
        /usr/bin/python3 validation/body_solver_benchmark.py --report-only   (rewrite the report)
The binary must be built with ``--features petsc`` (``make build``).
Run it with nothing else running on the machine: timings are wall times.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

VALIDATION = Path(__file__).resolve().parent
import benchmark as bm  # noqa: E402  (the shared helpers: meshes, measure, dolfinx worker)

REPO = VALIDATION.parent
REPORT = VALIDATION / "BODY_SOLVER_BENCHMARK.md"
COMMAND = "/usr/bin/python3 validation/body_solver_benchmark.py"

# Levels of geo/block_3d.geo; the first three are benchmark.py's 30k and 100k and a level
# between, the last the largest our CG + AMG was measured at from outside (670k).
SIZES = {
    "30k": bm.Size("30k", 1.15),
    "100k": bm.Size("100k", 1.78),
    "200k": bm.Size("200k", 2.13),
    "670k": bm.Size("670k", 2.735),
}
OURS = {"cholesky": "ours, Cholesky", "cg-amg": "ours, CG + AMG"}


def run_ours(binary: Path, case: Path, output: Path) -> dict:
    """One internodes solve: usage, the solver phases from summary.json, the displacement."""
    import h5py
    import shutil

    shutil.rmtree(output, ignore_errors=True)
    usage = bm.measure([binary, "solve", case, "--quiet", "--output", output], output.with_suffix(".log"))
    summary = json.loads((output / "summary.json").read_text())
    (body,) = [b for b in summary["bodies"] if b["name"] == bm.BODY]
    solve = body["solve"]
    phases = dict(solve["timings"])
    setup = sum(phases.get(p, 0.0) for p in ("ordering + symbolic", "numeric factorization", "CG + AMG setup"))
    solution = sum(phases.get(p, 0.0) for p in ("triangular solves", "CG + AMG solve"))
    with h5py.File(output / "solution.h5", "r") as f:
        np.save(output.with_suffix(".u.npy"), f["/fields/displacement"][:])
    return usage | {"dofs": body["num_dofs"], "solver": solve.get("body_solver"),
                    "iterations": solve.get("cg_iterations"), "setup": setup, "solve": solution,
                    "assemble": phases["sparsity pattern"] + phases["assemble stiffness"],
                    "relative_residual": solve["relative_residual"], "phases": phases}


def benchmark_size(size: bm.Size, binary: Path) -> dict:
    """Mesh, case files, the three runs, and the displacement differences."""
    bm.generate_mesh(size)
    base = bm.write_cases(size)["base"]
    runs: dict[str, dict] = {}
    for kind, label in OURS.items():
        case = size.folder / f"block_3d_{kind}.toml"
        case.write_text(f'{base.read_text()}\n[solver]\nbody = "{kind}"\n')
        print(f"   {label} ...", end=" ", flush=True)
        try:
            runs[kind] = run_ours(binary, case, size.folder / f"body_{kind}")
            print(f"{runs[kind]['wall']:.1f} s, {runs[kind]['peak_mb']:.0f} MB", flush=True)
        except (bm.RunFailed, OSError, KeyError, ValueError) as error:
            runs[kind] = {"error": f"{type(error).__name__}: {error}"}
            print(f"FAILED ({runs[kind]['error']})", flush=True)
    print("   dolfinx, CG + GAMG ...", end=" ", flush=True)
    try:
        coordinates = next(size.folder / f"body_{k}" / "solution.h5" for k in ("cg-amg", "cholesky")
                           if "error" not in runs[k])
        runs["dolfinx"] = bm.run_dolfinx("cg", {"base": base}, coordinates, size.folder / "body_dolfinx_cg")
        print(f"{runs['dolfinx']['wall']:.1f} s, {runs['dolfinx']['peak_mb']:.0f} MB", flush=True)
    except (StopIteration, bm.RunFailed, OSError, KeyError, ValueError) as error:
        runs["dolfinx"] = {"error": f"{type(error).__name__}: {error}"}
        print(f"FAILED ({runs['dolfinx']['error']})", flush=True)
    u = {}
    for run, path in (("cholesky", "body_cholesky"), ("cg-amg", "body_cg-amg"), ("dolfinx", "body_dolfinx_cg")):
        if "error" not in runs[run]:
            u[run] = np.load(size.folder / f"{path}.u.npy").reshape(-1)
    differences = {}
    for a, b in (("cg-amg", "cholesky"), ("cg-amg", "dolfinx"), ("dolfinx", "cholesky")):
        if a in u and b in u:
            differences[f"{a} vs {b}"] = bm.relative_l2(u[a], u[b])
    return {"name": size.name, "level": size.level, "nodes": bm.mesh_nodes(size.mesh),
            "runs": runs, "differences": differences}


def git(*args: str) -> str:
    return subprocess.run(["git", *args], capture_output=True, text=True, cwd=REPO).stdout.strip()


def cell(run: dict, key: str, digits: int = 3) -> str:
    if "error" in run:
        return bm.status(run)
    return bm.fmt(run.get(key), digits)


def table(sizes: list[dict]) -> list[list[str]]:
    rows = [["DOFs", "Chol. setup", "Chol. solve", "Chol. wall", "Chol. MB",
             "CG+AMG setup", "CG+AMG solve (its)", "CG+AMG wall", "CG+AMG MB",
             "dfx setup", "dfx solve (its)", "dfx wall", "dfx MB",
             "Δu CG/Chol.", "Δu CG/dfx"]]
    for size in sizes:
        ch, cg, dfx = size["runs"]["cholesky"], size["runs"]["cg-amg"], size["runs"]["dolfinx"]
        dofs = next((r["dofs"] for r in (cg, ch, dfx) if "dofs" in r), 3 * size["nodes"])
        its = lambda r, key="iterations": f" ({r[key]})" if "error" not in r and r.get(key) else ""  # noqa: E731
        dfx_setup = dfx.get("timings", {}).get("setup")
        dfx_solve = dfx.get("timings", {}).get("solve")
        d = size["differences"]
        rows.append([f"{dofs:,}", cell(ch, "setup"), cell(ch, "solve"), cell(ch, "wall"), cell(ch, "peak_mb"),
                     cell(cg, "setup"), cell(cg, "solve") + its(cg), cell(cg, "wall"), cell(cg, "peak_mb"),
                     bm.fmt(dfx_setup) if "error" not in dfx else bm.status(dfx),
                     (bm.fmt(dfx_solve) + its(dfx)) if "error" not in dfx else bm.status(dfx),
                     cell(dfx, "wall"), cell(dfx, "peak_mb"),
                     f"{d['cg-amg vs cholesky']:.1e}" if "cg-amg vs cholesky" in d else "-",
                     f"{d['cg-amg vs dolfinx']:.1e}" if "cg-amg vs dolfinx" in d else "-"])
    return rows


def notes(sizes: list[dict]) -> list[str]:
    """Errors and loads of the runs, one line each."""
    lines = []
    for size in sizes:
        for run, result in size["runs"].items():
            if "error" in result:
                lines.append(f"* {size['name']}, {run}: {result['error']}")
    loads = [r["load_before"] for s in sizes for r in s["runs"].values() if "load_before" in r]
    if loads:
        lines.append(f"* 1-minute load average before the runs: {min(loads):.1f} to {max(loads):.1f} "
                     f"(2 cores; the machine is shared).")
    return lines


def _ok(run: dict) -> bool:
    return "error" not in run


def reading(sizes: list[dict]) -> list[str]:
    """The table's ratios in words."""
    lines = []
    both = [s for s in sizes if _ok(s["runs"]["cholesky"]) and _ok(s["runs"]["cg-amg"])]
    if both:
        speed = ", ".join(f"{(s['runs']['cholesky']['setup'] + s['runs']['cholesky']['solve']) / (s['runs']['cg-amg']['setup'] + s['runs']['cg-amg']['solve']):.1f}x" for s in both)
        memory = ", ".join(f"{s['runs']['cholesky']['peak_mb'] / s['runs']['cg-amg']['peak_mb']:.1f}x" for s in both)
        lines.append(f"**CG + AMG against Cholesky** (ours, {', '.join(s['name'] for s in both)}): "
                     f"Cholesky's factorization + solve takes {speed} the time of CG + AMG's setup + solve, "
                     f"and its process {memory} the peak memory. A factor is worth it only for many "
                     f"right-hand sides (a contact solve) or small bodies (`auto`'s threshold).")
    pairs = [s for s in sizes if _ok(s["runs"]["cg-amg"]) and _ok(s["runs"]["dolfinx"])]
    if pairs:
        def ratio(s: dict, ours: str, theirs: str) -> float:
            return s["runs"]["cg-amg"][ours] / s["runs"]["dolfinx"]["timings"][theirs]
        setup = ", ".join(f"{ratio(s, 'setup', 'setup'):.2f}x" for s in pairs)
        solve = ", ".join(f"{ratio(s, 'solve', 'solve'):.2f}x" for s in pairs)
        its = ", ".join(f"{s['runs']['cg-amg']['iterations']} / {s['runs']['dolfinx']['iterations']}" for s in pairs)
        wall = ", ".join(f"{s['runs']['cg-amg']['wall'] / s['runs']['dolfinx']['wall']:.2f}x" for s in pairs)
        memory = ", ".join(f"{s['runs']['cg-amg']['peak_mb'] / s['runs']['dolfinx']['peak_mb']:.2f}x" for s in pairs)
        lines.append(f"**Ours against dolfinx, both CG + GAMG** ({', '.join(s['name'] for s in pairs)}): setup "
                     f"{setup}, solve {solve} (iterations {its}: ours stop on the true residual, dolfinx on "
                     f"the preconditioned one), whole process {wall}, peak memory {memory}. Our setup "
                     f"includes PETSc's initialization and the copy of the matrix into PETSc; our process "
                     f"also keeps K and K_c for the reactions and the residual check.")
    return lines


def write_report(env: dict, sizes: list[dict], argv: list[str]) -> None:
    text = f"""# Body solvers: Cholesky, CG + AMG, dolfinx CG + GAMG

Written by `validation/body_solver_benchmark.py`; do not edit by hand. Regenerate with
`{COMMAND}` (binary built with `--features petsc`).

| item | value |
|---|---|
| date | {env['date']} |
| machine | {env['cpu']}, {env['nproc']} cores, {env['memory_gib']} GiB, {env['os']} |
| internodes | commit {env['commit']} (clean tree), {env['binary_version']}, {env['rustc']} |
| dolfinx / PETSc | {env['dolfinx']} / {env['petsc']} |
| this run | `{' '.join(argv)}` |

**Problem.** `geo/block_3d.geo` (block [-2,2]^2 x [-2,0], refined towards the origin), P1
tetrahedra, E = 1000, nu = 0.3, clamped base, Hertzian pressure on the top face
(`validation/cases/block_3d.toml`), mesh levels {', '.join(str(s['level']) for s in sizes)}.

## Results

Times in seconds (wall), memory in MB (peak resident set of the run's process).

{bm.markdown(table(sizes))}

* **Chol.** = ours, `[solver] body = "cholesky"`: *setup* = ordering + symbolic + numeric
  factorization, *solve* = triangular solves.
* **CG+AMG** = ours, `body = "cg-amg"`: *setup* = PETSc initialization (0.3 to 0.45 s, once per
  process) + matrix + GAMG hierarchy, *solve* = CG (iterations), stopping at
  ||f - K u|| / ||f|| <= 1e-10.
* **dfx** = dolfinx, serial, CG + GAMG with the rigid-body near-null space, rtol 1e-10 on the
  preconditioned residual (PETSc's default norm): *setup* = `ksp.setUp()`, *solve* = `ksp.solve`.
* *wall* = the whole process (mesh reading, assembly, output; for dolfinx also the Python
  start-up, form compilation and the gmsh model). *MB*: dolfinx's includes the interpreter.
* *Δu* = ||u_a - u_b|| / ||u_b|| (relative L2, nodes in our numbering).

{chr(10).join(notes(sizes))}

## Reading

{(chr(10) * 2).join(reading(sizes))}
"""
    REPORT.write_text(text)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", default=",".join(SIZES), help="comma-separated, of " + ", ".join(SIZES))
    parser.add_argument("--binary", type=Path, default=REPO / "target" / "release" / "internodes")
    parser.add_argument("--report-only", action="store_true",
                        help="rewrite the report from the last run's results (its commit and date)")
    parser.add_argument("--allow-dirty", action="store_true",
                        help="run from a modified tree (the report is then not written)")
    args = parser.parse_args()
    results = bm.BENCH / "body_solver_results.json"
    if args.report_only:
        saved = json.loads(results.read_text())
        write_report(saved["env"], saved["sizes"], saved["argv"])
        print(f"wrote {REPORT.relative_to(REPO)} from {results.relative_to(REPO)}")
        return 0
    dirty = git("status", "--porcelain")
    if dirty and not args.allow_dirty:
        print(f"the working tree is modified; commit first (or --allow-dirty):\n{dirty}", file=sys.stderr)
        return 2
    names = args.sizes.split(",")
    unknown = [n for n in names if n not in SIZES]
    if unknown:
        print(f"unknown sizes {unknown}; known: {', '.join(SIZES)}", file=sys.stderr)
        return 2
    env = bm.environment(args.binary)
    env["commit"] = git("rev-parse", "--short", "HEAD")
    env["date"] = datetime.datetime.now().astimezone().isoformat(timespec="seconds")
    sizes = []
    for name in names:
        print(f"{name} (level {SIZES[name].level}):", flush=True)
        sizes.append(benchmark_size(SIZES[name], args.binary))
    argv = [os.path.relpath(sys.argv[0], REPO), *sys.argv[1:]]
    results.write_text(json.dumps({"env": env, "sizes": sizes, "argv": argv}, indent=2))
    print(bm.markdown(table(sizes)))
    for line in notes(sizes):
        print(line)
    if dirty:
        print("(modified tree: report not written)")
    else:
        write_report(env, sizes, argv)
        print(f"wrote {REPORT.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
