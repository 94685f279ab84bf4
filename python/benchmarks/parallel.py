"""Solves run side by side from Python threads: wall-clock time of the same solves in turn and
by two workers, each solve with `threads` solver threads in a pool of its own.

    build/venv/bin/python python/benchmarks/parallel.py [--solves 4] [--repeat 1]

Prints one line per configuration and the speed-up of two workers over one. The 3D hemisphere
on a block (the mesh of geo/hemisphere_on_block.toml), pressed by different approaches, one
load step each. Timings depend on the machine and on what else runs on it: a benchmark, not a
test. "cores busy" (CPU over wall-clock seconds) near the workers' count says that they ran side
by side; on a machine busy with other work it stays low whatever this module does (compare two
processes, e.g. two copies of this script at once).
"""

import argparse
import os
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import internodes

REPO = Path(__file__).resolve().parents[2]


def case(approach):
    body = lambda name, group, uz: {  # noqa: E731
        "name": name, "youngs_modulus": 1e3, "poisson_ratio": 0.3,
        "dirichlet": [{"group": group, "ux": 0.0, "uy": 0.0, "uz": uz}]}
    return internodes.Case.from_dict({
        "contact": {"bodies": ["sphere", "block"], "surfaces": ["sphere_contact", "block_contact"]},
        "body": [body("sphere", "sphere_top", -approach), body("block", "block_base", 0.0)],
    }, name=f"approach {approach}")


def run(mesh, cases, workers, threads):
    """Wall-clock and CPU seconds of the solves, and their forces."""
    start, cpu = time.perf_counter(), time.process_time()
    with ThreadPoolExecutor(max_workers=workers) as pool:
        results = list(pool.map(lambda c: internodes.solve(c, mesh=mesh, threads=threads), cases))
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    assert all(r.status == "converged" for r in results), [r.status for r in results]
    return seconds, cpu, [r.summary["contact"]["force_primary"] for r in results]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--solves", type=int, default=4)
    parser.add_argument("--repeat", type=int, default=1, help="best of this many runs")
    args = parser.parse_args()
    mesh = internodes.Mesh.from_geo(REPO / "geo" / "hemisphere_on_block.geo",
                                    {"h_c": 0.015, "r_c": 0.16, "h_far": 0.5, "d_far": 1.0})
    cases = [case(0.004 + 0.002 * k) for k in range(args.solves)]
    cores = os.cpu_count()
    print(f"{args.solves} solves of {mesh}, {cores} cores")
    reference = None
    for threads in [1, None]:
        timings = {}
        for workers in [1, 2]:
            best = (float("inf"), 0.0)
            for _ in range(args.repeat):
                seconds, cpu, forces = run(mesh, cases, workers, threads)
                best = min(best, (seconds, cpu))
                reference = reference or forces
                assert forces == reference, "the answers depend on the threads"
            timings[workers] = best[0]
            print(f"threads={threads or 'default'}, {workers} worker(s): {best[0]:.2f} s "
                  f"(CPU {best[1]:.2f} s, {best[1] / best[0]:.2f} cores busy)")
        print(f"threads={threads or 'default'}: two workers {timings[1] / timings[2]:.2f}x as "
              "fast as one")


if __name__ == "__main__":
    main()
