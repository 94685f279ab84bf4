#!/usr/bin/python3
"""Wall times of the contact solve's interface solvers on the contact benchmark's problem.

The hemisphere on block of ``validation/contact_benchmark.py`` (``geo/hemisphere_on_block.toml``,
one step, the full displacement), at the levels given, with each of these set-ups:

  schur+cholesky    ``[contact] solver = "schur"``,  ``[solver] body = "cholesky"``
  krylov+cholesky   ``[contact] solver = "krylov"``, ``[solver] body = "cholesky"``
  krylov+cg-amg     ``[contact] solver = "krylov"``, ``[solver] body = "cg-amg"``

Each run is its own process, one after the other. Printed per run: DOFs, the wall time of the
process, the contact set-up and loop times (``summary.json``), the active-set iterations and
status, the final active primary nodes, the contact force, and for the Krylov runs the GMRES
iterations of each active-set iteration (from the verbose log).

Usage:  /usr/bin/python3 validation/interface_solver_timing.py [--levels 0.25 0.85] [--runs NAME ...]

Run it with nothing else running on the machine: timings are wall times.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path


from contact_benchmark import BENCH, ONE_STEP, REPO, Size, generate_mesh, write_case  # noqa: E402

RUNS = {
    "schur+cholesky": ("schur", "cholesky"),
    "krylov+cholesky": ("krylov", "cholesky"),
    "krylov+cg-amg": ("krylov", "cg-amg"),
}
GMRES_LINE = re.compile(r"^\s+interface GMRES: (\d+) iterations")


def run(binary: Path, size: Size, name: str) -> dict:
    solver, body = RUNS[name]
    case = write_case(size, name.replace("+", "_"), ONE_STEP)
    text = case.read_text().replace("[contact]", f'[solver]\nbody = "{body}"\n\n[contact]\nsolver = "{solver}"', 1)
    case.write_text(text)
    output = size.folder / f"out_{name}"
    shutil.rmtree(output, ignore_errors=True)
    log = output.with_suffix(".log")
    start = time.perf_counter()
    with log.open("w") as handle:
        result = subprocess.run([binary, "solve", case, "--output", output], stdout=handle,
                                stderr=subprocess.STDOUT)
    wall = time.perf_counter() - start
    summary_file = output / "summary.json"
    if not summary_file.is_file():
        tail = " | ".join(log.read_text().strip().splitlines()[-3:])
        return {"name": name, "error": f"exit {result.returncode}: {tail}", "wall": wall}
    summary = json.loads(summary_file.read_text())
    contact = summary["contact"]
    timings = dict(summary["timings"])
    gmres = [int(m.group(1)) for line in log.read_text().splitlines() if (m := GMRES_LINE.match(line))]
    return {
        "name": name, "wall": wall,
        "dofs": sum(b["num_dofs"] for b in summary["bodies"]),
        "set_up": timings["contact set-up"], "loop": timings["contact step 1"],
        "iterations": len(contact["iterations"]), "status": contact["status"],
        "active": contact["active_primary"],
        "force": contact["force_primary"][-1], "gmres": gmres,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--levels", type=float, nargs="+", default=[0.25, 0.85])
    parser.add_argument("--runs", nargs="+", choices=list(RUNS), default=list(RUNS))
    parser.add_argument("--binary", type=Path, default=REPO / "target/release/internodes")
    args = parser.parse_args()
    results = []
    for level in args.levels:
        size = Size(f"level{level}", level)
        generate_mesh(size)
        for name in args.runs:
            record = run(args.binary, size, name)
            record["level"] = level
            results.append(record)
            if "error" in record:
                print(f"level {level} {name}: {record['error']} ({record['wall']:.1f} s)", flush=True)
                continue
            print(f"level {level} {record['dofs']:>8,} DOFs {name:<16} wall {record['wall']:7.2f} s "
                  f"(set-up {record['set_up']:.2f}, loop {record['loop']:.2f}) its {record['iterations']} "
                  f"{record['status']} active {record['active']} force {record['force']:.6e} "
                  f"GMRES {record['gmres']}", flush=True)
    (BENCH / "interface_solver_timing.json").write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
