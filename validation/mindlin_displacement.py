#!/usr/bin/python3
"""The tangential displacement of a sphere sheared under partial slip, against Mindlin's, under
mesh refinement (3D Coulomb friction).

The hemisphere on the block of ``geo/hemisphere_on_block.geo`` (R = 1, one material, E = 1000,
nu = 0.3; the demo's geo parameters at refinement ``level``) is pressed by 0.01, then its top is
moved sideways by s = d/4, d/2, d (d = 0.0012) at that approach, mu = 0.3 (Q / (mu P) up to
about 0.4). Mindlin (1949; Johnson 1985, 7.2): the shear Q moves the two bodies' far points
relative to each other by

    delta(Q) = 3 mu P / (16 a G*) [1 - (1 - Q / (mu P))^(2/3)],
    1 / G* = (2 - nu_1) / G_1 + (2 - nu_2) / G_2,

which is Q / (8 a G*) when the whole zone sticks, and more when an annulus slips. The closed form
is for half-spaces: on these finite bodies the top's shift is s = Q C + delta(Q), with a bulk
compliance C of the meshes and supports that no closed form gives. Tied contact along the same
path (the whole zone held: s = Q_tied (C + 1 / (8 a G*))) measures it, so that what slip adds,

    measured:  s - Q s / Q_tied,        Mindlin:  delta(Q) - Q / (8 a G*),

is compared with no fitted constant. What slip adds is a small part of the shift (about a tenth
at Q / (mu P) = 0.4, less below), and on a mesh it is carried by the ring of nodes at the zone's
edge, where the discrete pressure falls to zero a spacing early: it converges as the spacing
h_c near the contact shrinks, which is what this script measures (h_c = 0.015 2^-level, a about
0.104). ``a`` is the solver's Hertz fit of the pressed step, P and Q its total contact force.

Writes ``validation/report/mindlin_displacement.md`` (date, machine, commit, the table); refuses
to write it from a tree with uncommitted changes to ``src/``.

``--curvature``: the same measure pressed in eight steps and sheared further (s = d, 3d/2, 2d:
Q / (mu P) up to 0.7, the slip annulus two to five spacings wide), at level 1 for the approaches
0.0025, 0.005 and 0.01 (``a / R`` about 0.05, 0.07 and 0.1; d scaled with the approach, which
keeps Q / (mu P) the same), and at levels 0 and 0.5 for the approach 0.01, whose zones have the
``a / h`` of the two smaller approaches at level 1 (about 7 and 10). Hertz and Mindlin's closed
forms are the limit ``a / R -> 0``: what the measured ratio owes to the sphere's curvature
shrinks with ``a / R`` at equal ``a / h``, what it owes to the mesh does not. Writes
``validation/report/mindlin_curvature.md``.

Usage:  /usr/bin/python3 validation/mindlin_displacement.py [--binary PATH] [--levels L ...] [--curvature]
"""

from __future__ import annotations

import argparse
import datetime
import json
import platform
import subprocess
import sys
from pathlib import Path

VALIDATION = Path(__file__).resolve().parent
REPO = VALIDATION.parent
sys.path.insert(0, str(VALIDATION))

from friction_cost import APPROACH, MU, SHEAR, case, mesh  # noqa: E402  (the same case, meshes cached by level)

BUILD = VALIDATION / "build" / "mindlin_displacement"
REPORT = VALIDATION / "report" / "mindlin_displacement.md"
CURVATURE_REPORT = VALIDATION / "report" / "mindlin_curvature.md"
SHEAR_FACTORS = [0.25, 0.5, 1.0]
CURVATURE_SHEAR_FACTORS = [1.0, 1.5, 2.0]
# (level, approach) of the curvature runs (module doc).
CURVATURE_RUNS = [(1.0, 0.0025), (1.0, 0.005), (1.0, 0.01), (0.0, 0.01), (0.5, 0.01)]
# The materials of both bodies in friction_cost.case.
E, NU = 1000.0, 0.3


def load_path(press_steps: int, factors: list[float]) -> tuple[list[float], list[float]]:
    """The factors of the press and of the shear: pressed in ``press_steps`` equal steps from a
    quarter of the approach (a smaller first zone is under two spacings across and is not
    solved to the accuracy report's bounds), then sheared at that approach."""
    first = 0.25 if press_steps > 1 else 1.0
    increment = (1.0 - first) / max(press_steps - 1, 1)
    press = [first + k * increment for k in range(press_steps)] + [1.0] * len(factors)
    shear = [0.0] * press_steps + factors
    return press, shear


def solve(binary: Path, case_file: Path, output: Path) -> dict:
    result = subprocess.run([str(binary), "solve", str(case_file), "--output", str(output), "--quiet"],
                            capture_output=True, text=True)
    # Exit 3 (solved, an accuracy indicator failed) is taken: the first press steps of a
    # small zone fail the secondary's sag, and each step's status is in the report.
    if result.returncode not in (0, 3):
        raise SystemExit(f"{case_file}: exit {result.returncode}\n{result.stderr[-2000:]}")
    return json.loads((output / "summary.json").read_text())


def measure(binary: Path, level: float, press_steps: int, approach: float = APPROACH,
            factors: list[float] = SHEAR_FACTORS) -> dict:
    """The measure of the module doc on one mesh and press; the shear ``d`` scaled with
    ``approach`` (``SHEAR`` at ``APPROACH``)."""
    msh = mesh(level)
    d = SHEAR * approach / APPROACH
    runs = {}
    for formulation in ("coulomb", "tied"):
        name = f"level{level}-press{press_steps}" + ("" if approach == APPROACH else f"-approach{approach}")
        output = BUILD / name / formulation
        press, shear = load_path(press_steps, factors)
        runs[formulation] = solve(binary, case(msh, formulation, output, tuple(press), tuple(shear),
                                               approach=approach, shift=d), output)
    coulomb, tied = runs["coulomb"]["contact"], runs["tied"]["contact"]
    g = E / (2.0 * (1.0 + NU))
    g_star = 1.0 / (2.0 * (2.0 - NU) / g)
    pressed = coulomb["steps"][press_steps - 1]
    a = pressed["hertz_a"]
    stiffness_tied = abs(tied["steps"][-1]["force_primary"][0]) / (factors[-1] * d)
    rows = []
    for k, factor in enumerate(factors):
        step = coulomb["steps"][press_steps + k]
        shift = factor * d
        q, p = abs(step["force_primary"][0]), abs(step["force_primary"][2])
        ratio = q / (MU * p)
        delta = 3.0 * MU * p / (16.0 * a * g_star) * (1.0 - (1.0 - ratio) ** (2.0 / 3.0))
        expected = delta - q / (8.0 * a * g_star)
        measured = shift - q / stiffness_tied
        rows.append({"shift": shift, "ratio": ratio, "measured": measured, "expected": expected,
                     "delta": delta, "status": step["status"]})
    dofs = sum(b["num_dofs"] for b in runs["coulomb"]["bodies"])
    return {"level": level, "press_steps": press_steps, "h_c": 0.015 * 2.0 ** -level, "a": a, "dofs": dofs,
            "approach": approach,
            "slipping_pressed": pressed["friction"]["slip_nodes"],
            "in_contact_pressed": pressed["friction"]["slip_nodes"] + pressed["friction"]["stick_nodes"],
            "primary": coulomb["primary"], "rows": rows,
            "tied_statuses": [s["status"] for s in tied["steps"]]}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", type=Path, default=REPO / "target" / "release" / "internodes")
    parser.add_argument("--levels", type=float, nargs="+")
    parser.add_argument("--press-steps", type=int, nargs="+", default=[1, 4, 8])
    parser.add_argument("--curvature", action="store_true",
                        help="the approach study at one mesh (module doc); writes mindlin_curvature.md")
    args = parser.parse_args()
    if args.curvature:
        runs = [(level, 8, approach, CURVATURE_SHEAR_FACTORS) for level, approach in CURVATURE_RUNS
                if args.levels is None or level in args.levels]
        title, report = "Tangential displacement under partial slip against Mindlin's (3D): the sphere's curvature", \
            CURVATURE_REPORT
    else:
        runs = [(level, n, APPROACH, SHEAR_FACTORS) for level in (args.levels or [0.0, 0.5, 1.0])
                for n in args.press_steps]
        title, report = "Tangential displacement under partial slip against Mindlin's (3D)", REPORT
    results = []
    for level, press_steps, approach, factors in runs:
        result = measure(args.binary, level, press_steps, approach, factors)
        results.append(result)
        name = f"level {level}, approach {approach}, pressed in {press_steps}"
        print(f"{name}: {result['slipping_pressed']} of {result['in_contact_pressed']} nodes slip", flush=True)
        for row in result["rows"]:
            print(f"{name}: s {row['shift']:.2e}, Q/(mu P) {row['ratio']:.3f}, slip adds "
                  f"{row['measured']:.3e}, Mindlin {row['expected']:.3e}, ratio {row['measured'] / row['expected']:.3f}",
                  flush=True)
    commit = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", str(REPO), "status", "--porcelain", "--", "src", "Cargo.toml", "Cargo.lock"],
                           capture_output=True, text=True).stdout.strip()
    lines = [f"# {title}", "",
             "Written by `validation/mindlin_displacement.py`; do not edit by hand (the measure and why: its "
             "docstring).", "",
             f"Run {datetime.datetime.now(datetime.timezone.utc).isoformat(timespec='seconds')} at commit {commit} "
             f"on {platform.machine()}, the binary's default solvers, `primary = \"auto\"`.", "",
             "| level | h_c | DOFs | " + ("approach | " if args.curvature else "") + "primary | pressed in | "
             "slipping after the press | a (fit" + (", = a / R" if args.curvature else "") + ") | s | Q / (mu P) | "
             "slip adds: measured | Mindlin | measured / Mindlin | delta(Q) (Mindlin, whole) |",
             "|---|---|---|" + ("---|" if args.curvature else "") + "---|---|---|---|---|---|---|---|---|---|"]
    for result in results:
        approach = f"{result['approach']} | " if args.curvature else ""
        for row in result["rows"]:
            lines.append(f"| {result['level']} | {result['h_c']:.4f} | {result['dofs']} | {approach}{result['primary']} | "
                         f"{result['press_steps']} | {result['slipping_pressed']} of {result['in_contact_pressed']} | "
                         f"{result['a']:.4f} | {row['shift']:.1e} | {row['ratio']:.3f} | {row['measured']:.3e} | "
                         f"{row['expected']:.3e} | {row['measured'] / row['expected']:.3f} | {row['delta']:.3e} |")
    converged = all(r["status"] == "converged" for res in results for r in res["rows"]) and all(
        s == "converged" for res in results for s in res["tied_statuses"])
    lines += ["", "Every step of every run (Coulomb and tied) converged." if converged
              else "Not every step converged: see the statuses in the runs' summary.json.", ""]
    if dirty:
        print("src/ has uncommitted changes: the report is not written", file=sys.stderr)
        return 1
    # The binary must be built from this commit's code: newer than its last change to src/.
    changed = subprocess.run(["git", "-C", str(REPO), "log", "-1", "--format=%ct", "--", "src", "Cargo.toml",
                              "Cargo.lock"], capture_output=True, text=True).stdout.strip()
    if changed and args.binary.stat().st_mtime < int(changed):
        print(f"{args.binary} is older than the last commit to src/: rebuild it; the report is not written",
              file=sys.stderr)
        return 1
    report.parent.mkdir(parents=True, exist_ok=True)
    report.write_text("\n".join(lines))
    print(f"wrote {report}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
