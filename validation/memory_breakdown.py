#!/usr/bin/python3
"""Where the memory of a run goes, per rank: heaptrack at the heap's peak, grouped by part.

Runs ``internodes solve CASE`` under heaptrack (Debian's ``heaptrack``), on ``--ranks N``
MPI ranks (``mpirun``) or one process, then reads each rank's profile with
``heaptrack_print --flamegraph-cost-type peak`` (the bytes each call stack holds at the
moment the heap is largest: the rows sum to the peak) and sums the stacks by the first
function below that names a part of the solver (table ``PARTS``). Prints one table: a row per
part, a column per rank (in an order of their own: heaptrack names a profile by process id),
in MB.

The heap counts what was allocated; the resident memory (``summary.json``'s
``rank_peak_memory_mb``) counts the pages written, and can be smaller (memory allocated and
never touched) or larger (freed memory the allocator keeps).

Usage:  /usr/bin/python3 validation/memory_breakdown.py CASE.toml [--ranks 2] [--binary PATH]
Example (the 1M-DOF case of the contact benchmark, after ``make bench``):
        /usr/bin/python3 validation/memory_breakdown.py \\
            validation/build/contact_bench/1M/hemisphere_on_block_default_one.toml --ranks 2
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent

# (part, a function name in the stack): the first part whose function is on a stack takes it.
#
# faer's dense products (through the crate private-gemm-x86) reserve, on each thread's first
# product, a thread-local packing buffer of twice the L3 cache the processor reports (480 MiB on
# this machine's virtual processor: 1.0 GB), whichever part calls first (the RBF interpolation's
# supernodal LU, or the half-space preconditioner's dense LU). The heap counts the reservation; the
# resident memory only the pages a product writes (217k DOFs in one process: heap peak 1718 MB,
# resident peak 777 MB). So it is a part of its own.
PARTS = [
    ("faer dense-product buffer (reserved; mostly never written)", "private_gemm_x86"),
    ("PETSc: GAMG hierarchy (set-up)", "internodes_cgamg_set_up"),
    ("PETSc: matrix, KSP (create)", "internodes_cgamg_create"),
    # The whole Phi_MM's sparse LU, factored only where a solve needs it (rbf_patch.rs).
    ("RBF interpolation: whole factor of Phi_MM (where used)", "rbf_patch::whole_factor"),
    # The rows of Phi_MM and Phi_NM a process holds, the sources' trees, D_NN (before
    # 2026-12-07 the whole Phi_MM, Phi_NM and Phi_MM's graph on every rank, under
    # `Interpolation::new`).
    ("RBF interpolation: set-up", "Interpolation::shared"),
    ("RBF interpolation: set-up", "Interpolation::new"),
    ("RBF interpolation: rows and columns", "rbf::Interpolation::"),
    # The patches' solves, on rayon's threads.
    ("RBF interpolation: rows and columns", "rbf_patch::"),
    ("coupled system blocks", "CoupledSystem::assemble"),
    # On several ranks each row and column is computed by one rank and its entries sent to
    # the ranks that keep them: what a rank keeps is allocated where they arrive, inside the
    # coupling's frame.
    ("RBF interpolation: rows and columns", "row_ownership::send_to_keepers"),
    ("interface coupling", "InterfaceOperators::coupling"),
    ("interface operators (other)", "InterfaceOperators::"),
    ("half-space preconditioner (S~^-1)", "HalfSpace::new"),
    # The two-level inverse's rows, computed on rayon's threads, whose stacks do not reach
    # HalfSpace::new.
    ("half-space preconditioner (S~^-1)", "two_level_inverse::"),
    ("GMRES basis and vectors", "gmres::"),
    ("coupled Krylov solve (other)", "coupled_krylov::"),
    ("mesh", "internodes::mesh::"),
    # The loop's, through functions of fem and Distribution: the interface forces kept as
    # fem::LoadVector's entries, the last iterate's displacements kept at a rank's rows.
    ("contact (other)", "CoupledSystem::solution"),
    ("contact (other)", "CoupledSolution::of_pair"),
    ("contact (other)", "row_ownership::complete_forces"),
    ("contact (other)", "BodyFactors::own_rows"),
    ("assembly: graph, partition, rows, loads", "internodes::elastic::"),
    ("assembly: graph, partition, rows, loads", "internodes::fem::"),
    ("assembly: graph, partition, rows, loads", "Distribution::"),
    # A rank's cells, received from rank 0 (`crate::parallel::scatter_cells`) into the body:
    # the partition's own graph and METIS have fem's frames above.
    ("mesh", "internodes::run::partition::"),
    ("contact (other)", "internodes::contact::"),
    ("output", "internodes::output::"),
    ("PETSc and MPI initialization", "internodes_petsc_initialize"),
]


def grouped(stacks: Path) -> dict[str, int]:
    """Bytes at the heap's peak per part, from one flame-graph file of heaptrack_print."""
    out: dict[str, int] = {}
    for line in stacks.read_text().splitlines():
        stack, _, count = line.rpartition(" ")
        part = next((name for name, function in PARTS if function in stack), "other")
        out[part] = out.get(part, 0) + int(count)
    return out


def breakdown(case: Path, ranks: int, binary: Path) -> tuple[list[dict[str, int]], dict, str]:
    """Runs ``case`` under heaptrack on ``ranks`` MPI ranks (one process for 1): the bytes at each
    rank's heap peak per part (ranks in an order of their own: heaptrack names a profile by
    process id), the run's ``summary.json`` and its log. Raises ``RuntimeError`` if the run
    fails."""
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        command = ["heaptrack", str(binary.resolve()), "solve", str(case.resolve()),
                   "-o", str(work / "out")]
        if ranks > 1:
            command = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-n", str(ranks), *command]
        # The environment as this script started (os.environ), not the process's own: dolfinx,
        # imported through suite.py, initializes MPI, which sets variables in the C environment
        # that make a child mpirun exit 1 without a word.
        run = subprocess.run(command, cwd=work, capture_output=True, text=True, env=dict(os.environ))
        if run.returncode not in (0, 2, 3):
            raise RuntimeError(f"{' '.join(command)} exited with {run.returncode}:\n{run.stdout}{run.stderr}")
        # heaptrack names a profile after the binary's file name and the process id.
        profiles = sorted(work.glob(f"heaptrack.{binary.name}.*.zst"), key=lambda p: int(p.name.split(".")[-2]))
        if len(profiles) != ranks:
            raise RuntimeError(f"expected {ranks} heaptrack profiles, found {len(profiles)}")
        columns = []
        for profile in profiles:
            stacks = profile.with_suffix(".stacks")
            subprocess.run(["heaptrack_print", "-f", str(profile), "--flamegraph-cost-type", "peak",
                            "-F", str(stacks)], check=True, capture_output=True)
            columns.append(grouped(stacks))
        summary = json.loads((work / "out" / "summary.json").read_text())
    return columns, summary, run.stderr


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("case", type=Path)
    parser.add_argument("--ranks", type=int, default=1)
    parser.add_argument("--binary", type=Path, default=REPO / "target/release/internodes")
    args = parser.parse_args()
    try:
        columns, _, _ = breakdown(args.case, args.ranks, args.binary)
    except RuntimeError as error:
        print(error, file=sys.stderr)
        return 1
    parts = [name for name, _ in PARTS] + ["other"]
    parts = list(dict.fromkeys(p for p in parts if any(p in c for c in columns)))
    parts.sort(key=lambda p: -max(c.get(p, 0) for c in columns))
    ranks = [f"a rank ({p + 1})" for p in range(len(columns))] if len(columns) > 1 else ["the process"]
    print(f"Heap at its peak, MB: {args.case} on {args.ranks} rank(s)")
    print()
    print("| part | " + " | ".join(ranks) + " |")
    print("|---|" + "---:|" * len(ranks))
    for part in parts:
        print(f"| {part} | " + " | ".join(f"{c.get(part, 0) / 1e6:.0f}" for c in columns) + " |")
    print("| **total (the heap's peak)** | " + " | ".join(f"**{sum(c.values()) / 1e6:.0f}**" for c in columns) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
