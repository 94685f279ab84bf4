#!/usr/bin/python3
"""Validation of internodes against FEniCSx (dolfinx 0.5.2): ``make validate``.

For every case file ``validation/cases/<case>.toml`` and every mesh level:

  1. mesh ``geo/<script>.geo`` with gmsh at that level (the case's ``mesh``
     entry names ``<script>_l<level>.msh``) into ``validation/build/meshes``;
  2. write the case file of that level (``mesh`` replaced) and run
     ``internodes solve CASE --output DIR --export-matrices``;
  3. build the dolfinx reference from the same mesh and case and compare
     (``compare.py``: matrices, displacements, reactions, strains, stresses).

Then print one table (check, case, figure, tolerance, PASS/FAIL) and write it
to ``validation/build/results.json``.

Then the contact suites (``suite.py``): the body-by-body FEniCSx check of
contact solutions (``body_by_body.py``), the Hertz suite with its convergence
study (``hertz_suite.py``), the independent dolfinx rigid-flat reference
(``rigid_flat.py``), the gated sweep of the contact solver over its required
parameter ranges (``sweep.py``; ``--quick``: its quick subset), the gated sweep of flat faces
in contact, flat blocks and stiff flat punches (``flat_sweep.py``; ``--quick``: its quick subset), the
gated sweep of contact at edges and corners off the other body's mesh lines (``edge_sweep.py``;
``--quick``: its quick subset), the gated suite of several contact pairs in one case (a three-block
stack against its exact solution, two discs on one block, a disc between two plates under a force;
``multi_body.py``; ``--quick``: its quick subset) and the refinement study with its grid convergence index against
Hertz (``refinement_study.py``; not run by ``--quick``). Everything goes into ``validation/report/`` (``report.py``):
README.md with every table and figure, and results.json.

Exit status 1 if a gate check failed or anything is missing (report.py says
which checks gate); missed accuracy targets are reported, not fatal.

Usage:  /usr/bin/python3 validation/run.py [--binary PATH] [--quick] [--levels L ...] [--reuse]
        [--cases C ...] [--suites S ...]
"""

from __future__ import annotations

import argparse
import json
import math
import re
import shutil
import subprocess
import sys
import time
import tomllib
from dataclasses import asdict
from pathlib import Path

VALIDATION = Path(__file__).resolve().parent
REPO = VALIDATION.parent

import importlib  # noqa: E402

import report  # noqa: E402
from compare import Check, compare_case, failure  # noqa: E402
from dolfinx_reference import ReferenceFailure, read_case  # noqa: E402
from suite import MeshFailed, SuiteResult, mesh_geo, run_solve  # noqa: E402

BUILD = VALIDATION / "build"
# The full run's report is committed; the quick run (make test) writes its own under build/.
REPORT = VALIDATION / "report"
QUICK_REPORT = BUILD / "report-quick"
# Contact suites: module name, whether its checks gate the run.
SUITES = {"body_by_body": True, "hertz_suite": False, "rigid_flat": False, "sweep": True, "flat_sweep": True,
          "edge_sweep": True, "multi_body": True, "refinement_study": False, "friction_suite": True,
          "penalty_suite": True, "akantu_suite": True}
# Regression bands on the target suites' figures, one section per mode.
BANDS = VALIDATION / "bands.json"
# A figure may grow to BAND_RELATIVE times its committed value plus BAND_ABSOLUTE before the band
# fails. The figures are deterministic for a given binary and mesh (results do not depend on the
# thread count, tests/threads.rs), so a band only has to absorb deliberate changes of the code
# that leave the method as it is (a refactoring moves figures at round-off); the changes that
# matter moved them by far more (the contact normal took the 2D rigid-flat force error from 1.15%
# to 0.53%). 1.25 x + 1e-3 (0.1% for relative errors, 0.001 h for distances) is the margin.
BAND_RELATIVE = 1.25
BAND_ABSOLUTE = 1e-3
DEFAULT_LEVELS = (0, 1)
MESH_NAME = re.compile(r"(?P<script>.+)_l(?P<level>-?\d+)\.msh")


class StepFailed(RuntimeError):
    """A step (meshing, solving) failed; the message says which and why."""


def parse_args() -> argparse.Namespace:
    """Command line: binary, levels."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--binary", type=Path, default=REPO / "target/release/internodes",
                        help="internodes executable (default: target/release/internodes)")
    parser.add_argument("--quick", action="store_true", help="coarsest level only (level 0)")
    parser.add_argument("--levels", type=int, nargs="+", default=DEFAULT_LEVELS,
                        help=f"mesh refinement levels (default: {' '.join(map(str, DEFAULT_LEVELS))})")
    parser.add_argument("--cases", nargs="+", help="case names (default: all of validation/cases)")
    parser.add_argument("--suites", nargs="*", default=list(SUITES),
                        help=f"contact suites to run (default: {' '.join(SUITES)}; none: --suites)")
    parser.add_argument("--write-bands", action="store_true",
                        help="record this run's target figures as the regression bands of its mode "
                             "(validation/bands.json) instead of checking them against the committed ones")
    parser.add_argument("--add-bands", action="store_true",
                        help="record a band for each target figure of this run that has none in its mode (a new "
                             "case's), leaving the committed bands as they are")
    parser.add_argument("--reuse", action="store_true",
                        help="Hertz suite: take each run's output from an earlier run of the same case, mesh and "
                             "binary (binary modification time included) instead of solving again")
    args = parser.parse_args()
    if args.quick:
        args.levels = [min(args.levels)]
    return args


def regression_bands(targets: list[SuiteResult], mode: str, write: bool, add: bool) -> SuiteResult:
    """Gate checks: every finite figure of the target suites within its committed band
    (``BAND_RELATIVE`` x the committed figure + ``BAND_ABSOLUTE``). With ``write``, this run's
    figures become the bands of ``mode`` first; with ``add``, only the figures without a band get
    one. A figure without a band fails: a new target must be recorded deliberately."""
    figures = {f"{c.check} | {c.case}": c.figure for suite in targets for c in suite.checks
               if math.isfinite(c.figure)}
    bands = json.loads(BANDS.read_text()) if BANDS.exists() else {}
    if write or add:
        kept = {} if write else bands.get(mode, {})
        recorded = {key: {"figure": value, "band": BAND_RELATIVE * value + BAND_ABSOLUTE}
                    for key, value in figures.items() if key not in kept}
        bands[mode] = dict(sorted((kept | recorded).items()))
        BANDS.write_text(json.dumps(bands, indent=1) + "\n")
    committed = bands.get(mode, {})
    checks = []
    for key, value in figures.items():
        check, case = key.split(" | ", 1)
        band = committed.get(key)
        if band is None:
            checks.append(failure(f"band: {check}", case, f"no committed band in {BANDS.name} ({mode}); a new "
                                                          f"case's is recorded by run.py --add-bands"))
        else:
            checks.append(Check(f"band: {check}", case, value, band["band"],
                                f"committed figure {band['figure']:.4g}"))
    return SuiteResult(title="Regression bands on the Hertz and rigid-flat figures", checks=checks,
                       text=f"Each finite figure of the target suites (but the refinement study's, which opts out: "
                            f"REGRESSION_BANDS in refinement_study.py) against its committed band ({BANDS.name}, "
                            f"mode {mode}): {BAND_RELATIVE} x the figure measured when the band was recorded, "
                            f"plus {BAND_ABSOLUTE:g}. A miss means the code moved a validated figure the wrong "
                            "way by more than a refactoring could.")


def run(command: list, what: str) -> None:
    """Run a command; on failure raise StepFailed with the end of its output."""
    result = subprocess.run([str(c) for c in command], capture_output=True, text=True)
    if result.returncode != 0:
        tail = "\n".join((result.stdout + result.stderr).strip().splitlines()[-5:])
        raise StepFailed(f"{what} failed (exit {result.returncode}): {tail}")


def geo_script(case_file: Path) -> str:
    """The geo script a case is meshed from: its ``mesh`` is ``.../<script>_l<level>.msh``."""
    with open(case_file, "rb") as f:
        mesh = Path(tomllib.load(f).get("mesh", ""))
    match = MESH_NAME.fullmatch(mesh.name)
    if match is None or not (REPO / "geo" / f"{match['script']}.geo").is_file():
        raise StepFailed(f"{case_file}: mesh '{mesh}' is not <script>_l<level>.msh with geo/<script>.geo existing")
    return match["script"]


def generate_mesh(script: str, level: int) -> Path:
    """geo/<script>.geo at ``level`` -> build/meshes/<script>_l<L>.msh (``suite.mesh_geo``)."""
    try:
        return mesh_geo(script, 3, {"level": level}, BUILD / "meshes" / f"{script}_l{level}.msh")
    except MeshFailed as error:
        raise StepFailed(str(error)) from error


def write_level_case(case_file: Path, mesh: Path, folder: Path) -> Path:
    """Copy of the case file in ``folder`` with ``mesh`` replaced (everything else verbatim)."""
    text, count = re.subn(r'(?m)^mesh\s*=.*$', f"mesh = {json.dumps(str(mesh))}", case_file.read_text())
    if count != 1:
        raise StepFailed(f"{case_file}: expected exactly one top-level 'mesh = ...' line, found {count}")
    folder.mkdir(parents=True, exist_ok=True)
    level_case = folder / case_file.name
    level_case.write_text(text)
    return level_case


def validate_level(binary: Path, case_file: Path, script: str, level: int, timings: dict) -> list[Check]:
    """Steps 1-3 for one case at one level; returns its checks."""
    label = f"{case_file.stem}_l{level}"
    folder = BUILD / label

    # 1. Mesh the geo script at this level.
    start = time.perf_counter()
    mesh = generate_mesh(script, level)
    timings["mesh"] = time.perf_counter() - start

    # 2. Solve with internodes, exporting the matrices.
    start = time.perf_counter()
    level_case = write_level_case(case_file, mesh, folder)
    output = folder / "internodes"
    shutil.rmtree(output, ignore_errors=True)  # never compare stale output
    solved = run_solve(binary, level_case, output, extra=("--export-matrices",))
    if solved.exit != 0:
        raise StepFailed(f"internodes solve {level_case} failed (exit {solved.exit}): {solved.tail(5)}")
    timings["internodes"] = time.perf_counter() - start

    # 3. dolfinx reference from the same mesh and case file, and comparison.
    start = time.perf_counter()
    checks = compare_case(read_case(level_case), output, label)
    timings["dolfinx + compare"] = time.perf_counter() - start
    return checks


def print_table(checks: list[Check]) -> None:
    """One row per check: check, case, figure, tolerance, PASS/FAIL, note."""
    header = f"{'#':>3}  {'check':<17} {'case':<38} {'figure':>10} {'tolerance':>9}  result  note"
    print(header)
    print("-" * len(header))
    for i, c in enumerate(checks, 1):
        print(f"{i:>3}  {c.check:<17} {c.case:<38} {c.figure:>10.2e} {c.tolerance:>9.0e}  "
              f"{'PASS' if c.passed else 'FAIL':<6}  {c.note}")


def main() -> int:
    """Run every case at every level, print and save the table; 0 if all checks pass."""
    args = parse_args()
    # The committed report must describe a commit: refuse to start from uncommitted changes.
    if not args.quick:
        dirty = subprocess.run(["git", "-C", str(REPO), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True).stdout.strip()
        if dirty:
            print("run.py: the tree has uncommitted changes; commit them first, so that the report "
                  "written to validation/report/ names the code it describes:\n" + dirty, file=sys.stderr)
            return 2
    report.COMMIT = subprocess.run(["git", "-C", str(REPO), "describe", "--always", "--dirty"],
                                   capture_output=True, text=True).stdout.strip() or None
    cases = sorted((VALIDATION / "cases").glob("*.toml"))
    if args.cases:
        cases = [VALIDATION / "cases" / f"{name}.toml" for name in args.cases]
    checks: list[Check] = []
    timings: dict[str, dict[str, float]] = {}

    # 0. The binary must exist and answer `solve --help`.
    try:
        run([args.binary, "solve", "--help"], f"{args.binary} solve --help")
    except (StepFailed, OSError) as error:
        checks.append(failure("binary", str(args.binary), str(error)))
        cases = []

    for case_file in cases:
        try:
            script = geo_script(case_file)
        except (StepFailed, OSError) as error:
            checks.append(failure("case file", case_file.stem, str(error)))
            continue
        for level in args.levels:
            label = f"{case_file.stem}_l{level}"
            timings[label] = {}
            print(f"== {label}", flush=True)
            try:
                checks += validate_level(args.binary, case_file, script, level, timings[label])
            except (StepFailed, ReferenceFailure, OSError, ValueError) as error:
                checks.append(failure("run", label, f"{type(error).__name__}: {error}"))
            print("   " + ", ".join(f"{phase} {seconds:.2f} s" for phase, seconds in timings[label].items()),
                  flush=True)

    # 4. One table, also as JSON.
    print()
    print_table(checks)
    num_passed = sum(c.passed for c in checks)
    print(f"\nvalidation: {num_passed} passed, {len(checks) - num_passed} failed")
    BUILD.mkdir(parents=True, exist_ok=True)
    results = {"binary": str(args.binary), "levels": list(args.levels), "timings": timings,
               "checks": [asdict(c) | {"figure": None if math.isnan(c.figure) else c.figure, "passed": c.passed}
                          for c in checks]}
    (BUILD / "results.json").write_text(json.dumps(results, indent=2))
    print(f"results written to {BUILD / 'results.json'}")

    # 5. The contact suites, then the report.
    gate = [SuiteResult(title="FEniCSx cross-checks: matrices and single-body solutions", checks=checks,
                        text="Stiffness and surface mass matrices, displacements, reactions, strains and "
                             "stresses of single-body solves against dolfinx on the same mesh and case "
                             "(`validation/README.md`); levels " + ", ".join(map(str, args.levels)) + ".")]
    targets, banded = [], []
    report_dir = QUICK_REPORT if args.quick else REPORT
    for name in args.suites:
        print(f"== suite {name}", flush=True)
        start = time.perf_counter()
        try:
            module = importlib.import_module(name)
            if hasattr(module, "REUSE"):
                module.REUSE = args.reuse
            result = module.run_suite(args.binary, args.quick, report_dir / name)
        except Exception as error:  # a suite that crashes is a failed gate check, with its reason
            result = SuiteResult(title=name, checks=[failure("suite", name, f"{type(error).__name__}: {error}")])
            gate.append(result)
        else:
            (gate if SUITES.get(name, True) else targets).append(result)
            # A target suite whose figures are too sensitive for a band says so (REGRESSION_BANDS).
            if not SUITES.get(name, True) and getattr(module, "REGRESSION_BANDS", True):
                banded.append(result)
        for c in result.checks:
            print(f"   {'PASS' if c.passed else 'FAIL'}  {c.check}: {c.case}: {c.figure:.3g} (<= {c.tolerance:g})")
        print(f"   {time.perf_counter() - start:.1f} s", flush=True)
    gate.append(regression_bands(banded, "quick" if args.quick else "full", args.write_bands, args.add_bands))
    command = "make validate" if not args.quick else "make test (run.py --quick)"
    counts = report.write(report_dir, gate, targets, command)
    print(f"\nreport written to {report_dir / 'README.md'}")
    # Only the complete run speaks for the project: it alone rewrites the README's headline.
    complete = not args.quick and list(args.levels) == list(DEFAULT_LEVELS) and set(args.suites) == set(SUITES)
    if complete and report.update_readme(REPO / "README.md", counts):
        print(f"headline table updated in {REPO / 'README.md'}")
    print(f"gate checks: {counts['gate_passed']} passed, {counts['gate_failed']} failed; "
          f"targets: {counts['targets_met']} met, {counts['targets_missed']} missed")
    return 0 if counts["gate_failed"] == 0 and counts["gate_passed"] > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
