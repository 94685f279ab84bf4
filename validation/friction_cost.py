#!/usr/bin/python3
"""What a frictional load step costs against a frictionless one, on the contact benchmark's
99k-DOF hemisphere on block (``contact_benchmark.py``'s size "99k": geo/hemisphere_on_block.geo
with the demo's geo parameters at level 0.85).

Both runs follow the same load path, each a separate process with the binary's default
solvers: step 1 presses the sphere's top down by 0.01 (path "press"), step 2 holds it there and
moves it sideways by ``SHEAR`` (path "shear"). One run is frictionless (the shear slides the
sphere over the block), the other Coulomb with mu = 0.3 (the shear is taken up by partial
slip, Q / (mu P) about 0.4). The figure is the second step's wall time (the "contact step 2"
timing of ``summary.json``) of the frictional run over the frictionless run's, with each run's
active-set iterations and GMRES iterations of that step (from the log). The aim: at most 1.5.

Writes ``validation/FRICTION_COST.md`` (date, machine, commit, the table) beside the contact
benchmark's report; refuses to write it from a tree with uncommitted changes to ``src/``.

Usage:  /usr/bin/python3 validation/friction_cost.py [--binary PATH] [--level L]
"""

from __future__ import annotations

import argparse
import datetime
import json
import platform
import re
import subprocess
import sys
import time
from pathlib import Path

VALIDATION = Path(__file__).resolve().parent
REPO = VALIDATION.parent
BUILD = VALIDATION / "build" / "friction_cost"
GEO = REPO / "geo" / "hemisphere_on_block.geo"
GEO_PARAMETERS = {"h_c": 0.015, "r_c": 0.16, "h_far": 0.5, "d_far": 1.0}
APPROACH = 0.01
SHEAR = 0.0012
MU = 0.3
AIM = 1.5
REPORT = VALIDATION / "FRICTION_COST.md"


def mesh(level: float) -> Path:
    path = BUILD / f"hemisphere_on_block_level{level}.msh"
    if not path.is_file():
        BUILD.mkdir(parents=True, exist_ok=True)
        parameters = dict(GEO_PARAMETERS, level=level)
        numbers = [a for k, v in parameters.items() for a in ("-setnumber", k, str(v))]
        subprocess.run(["gmsh", "-3", str(GEO), *numbers, "-format", "msh41", "-o", str(path), "-v", "1"],
                       check=True, capture_output=True)
    return path


def case(msh: Path, formulation: str, output: Path, press: tuple[float, ...] = (1.0, 1.0),
         shear: tuple[float, ...] = (0.0, 1.0), approach: float = APPROACH, shift: float = SHEAR) -> Path:
    """The case file of one run, beside ``output``: the sphere's top pressed down by
    ``approach`` times the factors ``press`` and moved along x by ``shift`` times ``shear``."""
    friction = f"\nfriction_coefficient = {MU}" if formulation == "coulomb" else ""
    text = f"""mesh = {json.dumps(str(msh))}
output = {json.dumps(str(output))}

[load_path]
press = [{", ".join(str(f) for f in press)}]
shear = [{", ".join(str(f) for f in shear)}]

[contact]
bodies = ["sphere", "block"]
surfaces = ["sphere_contact", "block_contact"]
primary = "auto"
formulation = "{formulation}"{friction}

[[body]]
name = "sphere"
youngs_modulus = 1000.0
poisson_ratio = 0.3

[[body.dirichlet]]
group = "sphere_top"
uz = {-approach}
path = "press"

[[body.dirichlet]]
group = "sphere_top"
ux = {shift}
uy = 0.0
path = "shear"

[[body]]
name = "block"
youngs_modulus = 1000.0
poisson_ratio = 0.3

[[body.dirichlet]]
group = "block_base"
ux = 0.0
uy = 0.0
uz = 0.0
"""
    output.parent.mkdir(parents=True, exist_ok=True)
    path = output.parent / f"{output.name}.toml"
    path.write_text(text)
    return path


def run(binary: Path, case_file: Path, output: Path) -> dict:
    start = time.perf_counter()
    # -vv: the active-set iterations (-v) and the coupled GMRES lines (-vv) are not in the
    # default log.
    result = subprocess.run([str(binary), "solve", str(case_file), "--output", str(output), "-vv"],
                            capture_output=True, text=True)
    wall = time.perf_counter() - start
    if result.returncode != 0:
        raise SystemExit(f"{case_file.name}: exit {result.returncode}\n{result.stderr[-2000:]}")
    summary = json.loads((output / "summary.json").read_text())
    contact = summary["contact"]
    timings = dict(summary.get("timings", {})) if isinstance(summary.get("timings"), dict) else {}
    step_seconds = [s["seconds"] for s in contact["steps"]]
    # The log's lines of the second step: its active-set iterations and GMRES iterations.
    log = result.stderr + result.stdout
    second = log.split("load step 2/2", 1)[-1]
    # Anchored at the line's start: a progress line of a long iteration
    # ("  iteration 5: 5 s (coupled GMRES: 17 iterations, ...)") matches neither.
    gmres = [int(n) for n in re.findall(r"^\s+coupled GMRES: (\d+) iterations", second, re.M)]
    iterations = len(re.findall(r"^\s+iteration +\d+: active", second, re.M))
    return {"wall": wall, "steps": step_seconds, "iterations": iterations, "gmres": sum(gmres),
            "statuses": [s["status"] for s in contact["steps"]], "dofs": sum(b["num_dofs"] for b in summary["bodies"]),
            "friction": contact["steps"][-1].get("friction"), "timings": timings}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", type=Path, default=REPO / "target" / "release" / "internodes")
    parser.add_argument("--level", type=float, default=0.85)
    args = parser.parse_args()
    msh = mesh(args.level)
    runs = {}
    for formulation in ("frictionless", "coulomb"):
        output = BUILD / formulation
        runs[formulation] = run(args.binary, case(msh, formulation, output), output)
    frictionless, coulomb = runs["frictionless"], runs["coulomb"]
    ratio = coulomb["steps"][1] / frictionless["steps"][1]
    commit = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", str(REPO), "status", "--porcelain", "--", "src", "Cargo.toml", "Cargo.lock"],
                           capture_output=True, text=True).stdout.strip()
    lines = [f"{frictionless['dofs']} DOFs (level {args.level}), step 1 presses by {APPROACH}, step 2 shears by "
             f"{SHEAR} at that approach, mu = {MU}", "",
             "| run | statuses | step 1 (s) | step 2 (s) | step 2: active-set iterations | step 2: GMRES iterations "
             "| wall (s) |", "|---|---|---|---|---|---|---|"]
    for name, r in runs.items():
        lines.append(f"| {name} | {', '.join(r['statuses'])} | {r['steps'][0]:.1f} | {r['steps'][1]:.1f} "
                     f"| {r['iterations']} | {r['gmres']} | {r['wall']:.1f} |")
    friction = coulomb["friction"] or {}
    if friction:
        q = (sum(v * v for v in friction["tangential_force"])) ** 0.5
        lines += ["", f"Coulomb step 2: Q/(mu P) = {q / (MU * friction['normal_force']):.3f}, "
                      f"{friction['stick_nodes']} sticking and {friction['slip_nodes']} slipping nodes."]
    verdict = "met" if ratio <= AIM else "missed"
    lines += ["", f"**Frictional step over frictionless step: {ratio:.2f}** (aim <= {AIM}: {verdict})."]
    print(f"friction cost at {commit}:")
    print("\n".join(lines))
    if dirty:
        print(f"not writing {REPORT.name}: uncommitted changes under src/ ({dirty.splitlines()[0]} ...)")
        return 0
    cpu = next((line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                if line.startswith("model name")), platform.processor())
    header = ["# Friction cost: a frictional load step against a frictionless one", "",
              "Written by `validation/friction_cost.py`; do not edit by hand. Regenerate with", "",
              "```sh", "/usr/bin/python3 validation/friction_cost.py", "```", "",
              f"Run {datetime.datetime.now(datetime.timezone.utc).isoformat(timespec='seconds')} at commit {commit} "
              f"on {cpu}, {os_cpu_count()} cores; one run of each, the figures of that run (the machine is "
              f"noisy: compare ratios within one run only). The case is the contact benchmark's 99k-DOF hemisphere "
              f"on a block (`validation/CONTACT_BENCHMARK.md`), both runs with the binary's default solvers.", ""]
    REPORT.write_text("\n".join(header + lines) + "\n")
    print(f"wrote {REPORT}")
    return 0


def os_cpu_count() -> int:
    import os

    return os.cpu_count() or 0


if __name__ == "__main__":
    sys.exit(main())
