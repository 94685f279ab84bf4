"""Our penalty method against Akantu's (gate where Akantu converges; full runs only).

Akantu 5.0.7 (the Python wheel, installed for the validation only by ``make akantu`` into
``build/akantu``) has the penalty contact the original INTERNODES report compared with. Its
``penalty_linear`` resolution pushes each slave node out of the master surface by the force
``epsilon_n * overlap * nodal_area`` (``validation/akantu_penalty.py`` says where in its source):
``epsilon_n`` is a pressure per length of overlap, our ``eps`` (``docs/method.md`` 3.8), so the
two are matched as ``eps = epsilon_n``, with our penalty factor ``epsilon_n h / E*`` (``h`` and
``E*`` as our solver takes them: ``summary.json``'s ``penalty_stiffness`` at the factor 1).

The case: the half-disc of ``geo/half_disc_on_block.geo`` (R = 1, E = 1000, nu = 0.3, spacing
R/80 at the contact) pressed by 0.02 onto the block, the disc Akantu's slave and our primary, in
ten increments for Akantu (its Newton solver per increment) and one step for us (frictionless
contact does not depend on the path). Two set-ups:

- **rigid flat**: Akantu's master not deformable (``is_master_deformable = false``: the block
  receives no contact force and stays flat); ours a block of E = 1e9. Where Akantu converges, the
  two forces must agree within ``SHARE`` times our penalty overlap indicator (plus 1e-6): the two
  codes solve the same discrete problem (the same P1 disc, the same overlap, the same nodal
  lengths in the reference configuration) but for the nodal length each spring acts over, which
  Akantu may take on the deformed surface, a relative change of the order of the surface's strain
  (below 5% here); it changes the springs' stiffness by that much and so the force by that share of
  the penalty's own error, which the indicator bounds. An error of the matching (a factor 2 in
  ``eps``) would move the force by about the penalty error itself, ten times the bound.
- **deformable block** (both E = 1000): Akantu's two-body penalty contact. Reported, not gated:
  Akantu 5.0.7 applies half of the slave force (``alpha = 0.5``), assigns rather than adds the
  master nodes' shares, and assembles a tangent that is not its residual's derivative
  (``validation/akantu_penalty.py``); its Newton solver did not converge the whole load at any
  penalty tried. The report gives how far it got, its reactions on the two bodies, and ours at
  the same ``epsilon_n``.

Run alone: ``/usr/bin/python3 validation/akantu_suite.py [--binary PATH]`` (after ``make akantu``).
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from compare import Check  # noqa: E402
from suite import (SuiteResult, body_table, case_toml, checks_table, contact_table, json_safe,  # noqa: E402
                   mesh_geo, run_solve, standalone)

VALIDATION = Path(__file__).resolve().parent
REPO = VALIDATION.parent
BUILD = VALIDATION / "build" / "akantu_suite"
AKANTU_PYTHON = REPO / "build" / "akantu" / "bin" / "python"
RUNNER = VALIDATION / "akantu_penalty.py"
GEO = {"h_c": 0.0125, "r_c": 0.2, "h_far": 0.5}
DELTA = 0.02
INCREMENTS = 10
E, NU = 1000.0, 0.3
RIGID = 1.0e9
RIGID_PENALTIES = (1e3, 1e4, 1e5, 1e6, 1e7)
DEFORMABLE_PENALTIES = (1e2, 1e3, 1e4, 1e5)
SHARE = 0.05
FLOOR = 1e-6
TIMEOUT = 600.0


def akantu(msh: Path, epsilon: float, rigid: bool) -> dict:
    """Akantu's run (``akantu_penalty.py``'s JSON)."""
    out = BUILD / f"akantu-{'rigid' if rigid else 'deformable'}-{epsilon:g}.json"
    command = [str(AKANTU_PYTHON), str(RUNNER), "--mesh", str(msh), "--out", str(out), "--epsilon", str(epsilon),
               "--delta", str(DELTA), "--steps", str(INCREMENTS), "--youngs", str(E), "--poisson", str(NU)]
    if rigid:
        command.append("--rigid-master")
    result = subprocess.run(command, capture_output=True, text=True, timeout=TIMEOUT)
    if result.returncode != 0 or not out.is_file():
        raise RuntimeError(f"akantu_penalty.py failed: {(result.stdout + result.stderr)[-400:]}")
    return json.loads(out.read_text())


def ours(binary: Path, msh: Path, name: str, block_modulus: float, factor: float, delta: float = DELTA) -> dict:
    """Our penalty run at the penalty factor ``factor`` and approach ``delta``."""
    folder = BUILD / name
    folder.mkdir(parents=True, exist_ok=True)
    contact = contact_table(("disc", "block"), ("disc_contact", "block_contact"), method="penalty",
                            penalty=factor)
    bodies = [body_table("disc", E, NU, [("disc_top", {"ux": 0.0, "uy": -delta})]),
              body_table("block", block_modulus, NU, [("block_base", {"ux": 0.0, "uy": 0.0})])]
    path = folder / "case.toml"
    path.write_text(case_toml(msh, folder / "out", contact, bodies, f"akantu suite: {name}"))
    run = run_solve(binary, path, folder / "out", timeout=TIMEOUT, log=folder / "log.txt")
    summary = folder / "out" / "summary.json"
    if not summary.is_file():
        raise RuntimeError(f"{name}: no summary ({run.tail()})")
    contact = json.loads(summary.read_text())["contact"]
    indicators = {c["name"]: c["value"] for c in contact["accuracy"]["indicators"]}
    return {"status": contact["status"], "force": contact["force_primary"][1], "primary": contact["primary"],
            "eps": contact["penalty_stiffness"], "overlap_estimate": indicators["penalty overlap"],
            "block_force": -contact["force_secondary"][1]}


def run_suite(binary: Path, quick: bool, out_dir: Path, names: list[str] | None = None) -> SuiteResult:
    start = time.perf_counter()
    out_dir.mkdir(parents=True, exist_ok=True)
    title = "The penalty method against Akantu 5.0.7's (gate where Akantu converges)"
    if quick:
        return SuiteResult(title, [], [], "Not in the quick run (it needs `make akantu`).", {"quick": True})
    if not AKANTU_PYTHON.is_file():
        raise RuntimeError(f"{AKANTU_PYTHON} missing: `make akantu` installs Akantu for the validation")
    msh = mesh_geo("half_disc_on_block", 2, GEO, BUILD / "half_disc.msh")
    checks: list[Check] = []
    records: dict = {"rigid": {}, "deformable": {}}
    # Our eps at the factor 1, E* / h, for each block: the factor that matches epsilon_n.
    unit = {block: ours(binary, msh, f"unit-{block:g}", block, 1.0)["eps"] for block in (RIGID, E)}
    for epsilon in RIGID_PENALTIES:
        theirs = akantu(msh, epsilon, rigid=True)
        mine = ours(binary, msh, f"rigid-{epsilon:g}", RIGID, epsilon / unit[RIGID])
        records["rigid"][f"{epsilon:g}"] = {"akantu": theirs, "ours": mine}
        if not theirs["converged"]:
            continue
        difference = abs(mine["force"] / theirs["force"] - 1.0)
        bound = SHARE * mine["overlap_estimate"] + FLOOR
        checks.append(Check("agreement", f"rigid flat, epsilon_n {epsilon:g}", difference / bound, 1.0,
                            f"ours {mine['force']:.7g} ({mine['status']}, eps {mine['eps']:.4g}), Akantu "
                            f"{theirs['force']:.7g}: {difference:.2e} against {bound:.2e}"))
    checks.append(Check("akantu converged", "rigid flat",
                         sum(not r["akantu"]["converged"] for r in records["rigid"].values()), len(RIGID_PENALTIES) - 1,
                         "Akantu's rigid-master runs that did not converge (at least one must, for a comparison)"))
    for epsilon in DEFORMABLE_PENALTIES:
        theirs = akantu(msh, epsilon, rigid=False)
        done = [s for s in theirs["steps"] if s["converged"]]
        reached = done[-1]["delta"] if done else 0.0
        mine = ours(binary, msh, f"deformable-{epsilon:g}", E, epsilon / unit[E], reached or DELTA)
        records["deformable"][f"{epsilon:g}"] = {"akantu": theirs, "ours": mine, "reached": reached}
    seconds = time.perf_counter() - start
    return SuiteResult(title, checks, [], report_text(records, checks, seconds),
                       {"quick": False, "seconds": seconds, "records": json_safe(records)})


def report_text(records: dict, checks: list[Check], seconds: float) -> str:
    lines = [f"Akantu suite: {len(checks)} checks, {sum(not c.passed for c in checks)} failed; wall time "
             f"{seconds:.0f} s. The half-disc (R/80) pressed by {DELTA} in {INCREMENTS} increments (Akantu) or "
             "one step (ours); `epsilon_n` is Akantu's penalty, a pressure per length, and ours is matched to it.", "",
             "**Rigid flat** (Akantu's master not deformable; our block E = 1e9):", "",
             "| epsilon_n | Akantu: converged, force, largest overlap, Newton iterations per increment | ours: force, "
             "status, overlap indicator | difference |", "|---|---|---|---|"]
    for key, record in records["rigid"].items():
        theirs, mine = record["akantu"], record["ours"]
        last = theirs["steps"][-1] if theirs["steps"] else {}
        difference = (f"{mine['force'] / theirs['force'] - 1:+.2e}" if theirs["converged"] else
                      f"not compared: {theirs['error']}")
        force = "none" if theirs["force"] is None else f"{theirs['force']:.7g}"
        overlap = "none" if last.get("max_gap") is None else f"{last['max_gap']:.3g}"
        lines.append(f"| {key} | {theirs['converged']}, {force}, {overlap}, "
                     f"{[s['iterations'] for s in theirs['steps']]} | {mine['force']:.7g}, {mine['status']}, "
                     f"{mine['overlap_estimate']:.3g} | {difference} |")
    lines += ["", "**Deformable block** (both E = 1000; not gated: Akantu 5.0.7 applies half the slave force, assigns the "
              "master's, and its tangent is not its residual's derivative). Akantu's last converged increment, its "
              "reactions on the disc's top and the block's base, and ours at that approach:", "",
              "| epsilon_n | Akantu: increments converged, approach reached, disc / block reaction, error | ours at that "
              "approach: force, status |", "|---|---|---|"]
    for key, record in records["deformable"].items():
        theirs, mine = record["akantu"], record["ours"]
        done = [s for s in theirs["steps"] if s["converged"]]
        reaction = f"{done[-1]['force']:.4g} / {done[-1]['block_base_force']:.4g}" if done else "none"
        error = re.sub(r"\S*NLSNotConvergedException.*?\]", "Newton did not converge", theirs["error"] or "")
        error = error.splitlines()[0] if error else ""
        lines.append(f"| {key} | {len(done)} of {INCREMENTS}, {record['reached']:g}, {reaction}, {error} | "
                     f"{mine['force']:.5g}, {mine['status']} |")
    lines += checks_table(checks)
    return "\n".join(lines)


def main() -> int:
    return standalone(__doc__, set(), run_suite, "akantu_suite.json", BUILD, binary=True)


if __name__ == "__main__":
    sys.exit(main())
