"""The penalty method against INTERNODES and exact answers (gate).

``method = "penalty"`` relaxes the contact law to ``p = eps max(0, -g)``, ``eps = penalty E* / h``
(``docs/method.md`` 3.8); everything else is INTERNODES'. So on one mesh the penalty answer must
tend to the INTERNODES answer as the penalty grows, with an error of order ``1 / eps`` (the overlap
``p / eps`` takes a share of the approach proportional to it), and where the answer is known
exactly (a stack of blocks in uniaxial strain) each interface is a spring of stiffness ``eps`` per
unit area in series with the blocks.

Cases (each solved by INTERNODES and by the penalty method at the factors ``PENALTIES``):

- ``half-disc-2d``: a half-disc (R = 1) pressed by 0.02 onto a block of its material (2D Hertz);
- ``hemisphere-3d``: a hemisphere (R = 1) pressed by 0.01 onto a block (3D Hertz);
- ``punch-2d``: a flat stiff punch (E = 1e7, sharp corners) pressed by 0.002 onto a block;
- ``three-blocks-2d``, ``three-blocks-3d``: three blocks of three materials on rollers, two
  non-matching interfaces, the middle block held by its contacts alone, pushed by 0.01.

Checks (each a figure against its tolerance):

- ``solved``: every run ends ``converged`` (its residual checks pass; a soft penalty's accuracy
  report may fail, and must, where the overlap indicator exceeds 1%);
- ``order``: between consecutive factors ten apart, ``log10(e_k / e_10k)`` within 0.1 of 1, ``e``
  the force's relative distance from INTERNODES', where ``e_k`` is below 1% (a spring of compliance
  ``c / k`` in series with the bodies' ``C`` gives ``e = c / (c + k C)``, of order 1 once small);
- ``limit``: at the factor 1e8 the force within 1e-6 of INTERNODES' (the overlap is then 1e-8 of
  the approach, below the loop's own tolerance);
- ``overlap bound`` and ``overlap sharpness`` (single pairs): the accuracy report's penalty overlap
  indicator is an upper estimate of ``e``: ``e / estimate <= 1`` and ``estimate / e <= 5``;
- ``exact`` (the stacks): the force within 1e-9 of ``push / (sum 1 / M_i + sum 1 / eps_p)``, ``M``
  the constrained moduli, ``eps_p`` each interface's penalty as ``summary.json`` reports it.

Hertz's half-width (2D) or radius (3D) from the force, against the pressure's fitted one, for
INTERNODES and the default penalty, is information (the report's table).

Run alone: ``/usr/bin/python3 validation/penalty_suite.py [--quick] [--cases ...]``.
"""

from __future__ import annotations

import json
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import hertz_theory  # noqa: E402
from compare import Check  # noqa: E402
from suite import (SuiteResult, body_table, case_toml, checks_table, contact_table, json_safe,  # noqa: E402
                   mesh_geo, run_cases, run_solve, standalone)

VALIDATION = Path(__file__).resolve().parent
BUILD = VALIDATION / "build" / "penalty_suite"
PENALTIES = (1.0, 10.0, 100.0, 1000.0, 1e8)
DEFAULT_PENALTY = 100.0
LIMIT = 1e8
ORDER_TOLERANCE = 0.1
# The order is judged where the error is below this: a spring of compliance c / k in series with
# the bodies' compliance C gives e = c / (c + k C), of order 1 in 1 / k only once e is small.
ASYMPTOTIC = 0.01
LIMIT_TOLERANCE = 1e-6
SHARPNESS = 5.0
EXACT_TOLERANCE = 1e-9
# The loop's gaps settled to 1e-8 of a spacing (0.01 of the tolerance): its own error far below
# the smallest penalty error measured (2e-5 of the force at the factor 1000). At 1e-8 the half-disc
# stalled at 4.5e-8 spacings, the size of the P1 surface's kinks (`docs/method.md` 3.4).
PENETRATION_TOLERANCE = 1e-6
TIMEOUT = 600.0


@dataclass
class PenaltyCase:
    name: str
    script: str
    dim: int
    parameters: dict
    bodies: list[dict]
    pairs: list[dict]
    quick: bool
    radius: float | None = None
    constrained_moduli: list[float] = field(default_factory=list)
    push: float = 0.0

    def text(self) -> str:
        return f"{self.script}.geo, {len(self.pairs)} pair(s), penalties {', '.join(f'{k:g}' for k in PENALTIES)}"


def _constrained(e: float, nu: float) -> float:
    return e * (1 - nu) / ((1 + nu) * (1 - 2 * nu))


def _stack(dim: int) -> PenaltyCase:
    blocks = [("lower", 1000.0), ("middle", 3000.0), ("upper", 500.0)]
    vertical = "xyz"[dim - 1]
    rollers = {"ux": 0.0} if dim == 2 else {"ux": 0.0, "uy": 0.0}
    bodies = []
    for name, e in blocks:
        conditions = [(f"{name}_sides", rollers)]
        if name == "lower":
            conditions.append(("lower_base", {f"u{vertical}": 0.0}))
        if name == "upper":
            conditions.append(("upper_top", {f"u{vertical}": -0.01}))
        bodies.append(body_table(name, e, 0.3, conditions))
    pairs = [contact_table(("upper", "middle"), ("upper_contact", "middle_top")),
             contact_table(("middle", "lower"), ("middle_bottom", "lower_contact"))]
    return PenaltyCase(f"three-blocks-{dim}d", f"three_blocks_{dim}d", dim, {}, bodies, pairs, dim == 2,
                       constrained_moduli=[_constrained(e, 0.3) for _, e in blocks], push=0.01)


CASES = (
    PenaltyCase("half-disc-2d", "half_disc_on_block", 2, {"h_c": 0.0125, "r_c": 0.2, "h_far": 0.5},
                [body_table("disc", 1000.0, 0.3, [("disc_top", {"ux": 0.0, "uy": -0.02})]),
                 body_table("block", 1000.0, 0.3, [("block_base", {"ux": 0.0, "uy": 0.0})])],
                [contact_table(("disc", "block"), ("disc_contact", "block_contact"))], True, radius=1.0),
    _stack(2),
    PenaltyCase("hemisphere-3d", "hemisphere_on_block", 3, {"h_c": 0.015, "r_c": 0.16, "h_far": 0.5, "d_far": 1.0},
                [body_table("sphere", 1000.0, 0.3, [("sphere_top", {"ux": 0.0, "uy": 0.0, "uz": -0.01})]),
                 body_table("block", 1000.0, 0.3, [("block_base", {"ux": 0.0, "uy": 0.0, "uz": 0.0})])],
                [contact_table(("sphere", "block"), ("sphere_contact", "block_contact"))], False, radius=1.0),
    PenaltyCase("punch-2d", "punch_2d", 2, {},
                [body_table("punch", 1.0e7, 0.3, [("punch_top", {"ux": 0.0, "uy": -0.002})]),
                 body_table("block", 1000.0, 0.3, [("block_base", {"ux": 0.0, "uy": 0.0})])],
                [contact_table(("punch", "block"), ("punch_contact", "block_contact"))], False),
    _stack(3),
)


def solve(binary: Path, case: PenaltyCase, msh: Path, penalty: float | None) -> dict:
    """One run: INTERNODES (``penalty`` None) or the penalty method at that factor."""
    label = "internodes" if penalty is None else f"penalty-{penalty:g}"
    folder = BUILD / case.name / label
    folder.mkdir(parents=True, exist_ok=True)
    extra = {"penetration_tolerance": PENETRATION_TOLERANCE}
    if penalty is not None:
        extra |= {"method": "penalty", "penalty": penalty}
    pairs = [pair | extra for pair in case.pairs]
    # One pair: a [contact] table; several: [[contact]] tables.
    contact = pairs[0] if len(pairs) == 1 else pairs
    text = case_toml(msh, folder / "out", contact, case.bodies, f"penalty suite: {case.name}, {label}")
    path = folder / "case.toml"
    path.write_text(text)
    run = run_solve(binary, path, folder / "out", timeout=TIMEOUT, log=folder / "log.txt")
    summary_path = folder / "out" / "summary.json"
    if not summary_path.is_file():
        return {"exit": run.exit, "error": run.tail()}
    summary = json.loads(summary_path.read_text())
    contacts = summary["contacts"] if "contacts" in summary else [summary["contact"]]
    records = []
    for contact in contacts:
        force = contact["force_primary"]
        indicators = {c["name"]: c["value"] for c in contact["accuracy"]["indicators"]}
        fit = contact.get("hertz_fit") or {}
        records.append({"status": contact["status"], "force": abs(force[case.dim - 1]),
                        "penalty_stiffness": contact.get("penalty_stiffness"),
                        "overlap_estimate": indicators.get("penalty overlap"),
                        "iterations": len(contact["iterations"]), "hertz_a": fit.get("a")})
    return {"exit": run.exit, "pairs": records, "seconds": run.seconds}


def run_case(binary: Path, case: PenaltyCase) -> tuple[list[Check], dict]:
    msh = mesh_geo(case.script, case.dim, case.parameters, BUILD / "meshes" / f"{case.name}.msh")
    runs = {"internodes": solve(binary, case, msh, None)}
    for k in PENALTIES:
        runs[f"{k:g}"] = solve(binary, case, msh, k)
    checks: list[Check] = []
    failed = [name for name, run in runs.items()
              if "error" in run or any(p["status"] != "converged" for p in run["pairs"])]
    checks.append(Check("solved", case.name, len(failed), 0,
                        f"not converged: {', '.join(failed)}" if failed else f"{len(runs)} runs converged"))
    if failed:
        return checks, {"runs": runs}
    for p in range(len(case.pairs)):
        tag = case.name if len(case.pairs) == 1 else f"{case.name} pair {p + 1}"
        exact = runs["internodes"]["pairs"][p]["force"]
        error = {k: 1.0 - runs[f"{k:g}"]["pairs"][p]["force"] / exact for k in PENALTIES}
        for low, high in zip(PENALTIES[:3], PENALTIES[1:4]):
            if error[low] >= ASYMPTOTIC:
                continue
            order = math.log10(error[low] / error[high]) if error[low] > 0 and error[high] > 0 else math.nan
            checks.append(Check("order", f"{tag} {low:g}-{high:g}", abs(order - 1.0), ORDER_TOLERANCE,
                                f"order {order:.3f} (errors {error[low]:.3e}, {error[high]:.3e})"))
        checks.append(Check("limit", tag, abs(error[LIMIT]), LIMIT_TOLERANCE,
                            f"force {runs[f'{LIMIT:g}']['pairs'][p]['force']:.9g} against INTERNODES {exact:.9g}"))
        # A pair's indicator estimates its own overlap's share; a stack's force also loses the
        # other interface's (`docs/method.md` 3.8), which the exact check below measures.
        for k in PENALTIES[:4] if len(case.pairs) == 1 else ():
            estimate = runs[f"{k:g}"]["pairs"][p]["overlap_estimate"]
            checks.append(Check("overlap bound", f"{tag} {k:g}", error[k] / estimate, 1.0,
                                f"error {error[k]:.3e}, estimate {estimate:.3e}"))
            checks.append(Check("overlap sharpness", f"{tag} {k:g}", estimate / error[k], SHARPNESS,
                                f"estimate over error {estimate / error[k]:.2f}"))
        if case.constrained_moduli:
            for k in PENALTIES:
                record = runs[f"{k:g}"]["pairs"][p]
                springs = sum(1.0 / r["penalty_stiffness"] for r in runs[f"{k:g}"]["pairs"])
                sigma = case.push / (sum(1.0 / m for m in case.constrained_moduli) + springs)
                checks.append(Check("exact", f"{tag} {k:g}", abs(record["force"] / sigma - 1.0), EXACT_TOLERANCE,
                                    f"force {record['force']:.10g} against {sigma:.10g}"))
    return checks, {"runs": runs}


def hertz_rows(cases: list[PenaltyCase], records: dict) -> list[str]:
    rows = ["", "**Hertz** (information): the fitted half-width (2D) or radius (3D) against Hertz's at the run's "
            "force, E* = 1000 / (2 (1 - 0.09)):", "", "| case | method | force | a fitted | a Hertz | difference |",
            "|---|---|---|---|---|---|"]
    e_star = hertz_theory.contact_modulus([(1000.0, 0.3), (1000.0, 0.3)])
    for case in cases:
        runs = records.get(case.name, {}).get("runs", {})
        if case.radius is None or "internodes" not in runs:
            continue
        for label in ("internodes", f"{DEFAULT_PENALTY:g}"):
            pair = runs.get(label, {}).get("pairs", [{}])[0]
            if pair.get("hertz_a") is None:
                continue
            theory = hertz_theory.contact(pair["force"], case.radius, e_star, case.dim)["a"]
            method = "INTERNODES" if label == "internodes" else f"penalty {label}"
            rows.append(f"| {case.name} | {method} | {pair['force']:.6g} | {pair['hertz_a']:.5g} | {theory:.5g} "
                        f"| {pair['hertz_a'] / theory - 1:+.2%} |")
    return rows


def report_text(cases: list[PenaltyCase], checks: list[Check], records: dict, quick: bool, seconds: float) -> str:
    lines = [f"{'Quick subset' if quick else 'Penalty suite'}: {len(cases)} cases, {len(checks)} checks, "
             f"{sum(not c.passed for c in checks)} failed; wall time {seconds:.0f} s.", "",
             "**Forces** (each pair's force on its primary; relative distance from INTERNODES in brackets; "
             "the penalty overlap indicator after the slash; iterations):", "",
             "| case | pair | INTERNODES | " + " | ".join(f"penalty {k:g}" for k in PENALTIES) + " |",
             "|---|---|---|" + "---|" * len(PENALTIES)]
    for case in cases:
        runs = records.get(case.name, {}).get("runs", {})
        if "internodes" not in runs or "pairs" not in runs["internodes"]:
            lines.append(f"| {case.name} | | not run |" + " |" * len(PENALTIES))
            continue
        for p, base in enumerate(runs["internodes"]["pairs"]):
            cells = []
            for k in PENALTIES:
                pair = runs.get(f"{k:g}", {}).get("pairs", [None] * (p + 1))[p]
                cells.append("" if pair is None else
                             f"{pair['force']:.7g} [{1 - pair['force'] / base['force']:.2e}] / "
                             f"{pair['overlap_estimate']:.2e}; {pair['iterations']} it.")
            lines.append(f"| {case.name} | {p + 1} | {base['force']:.7g}; {base['iterations']} it. | "
                         + " | ".join(cells) + " |")
    lines += hertz_rows(cases, records)
    lines += checks_table(checks)
    return "\n".join(lines)


def run_suite(binary: Path, quick: bool, out_dir: Path, names: list[str] | None = None) -> SuiteResult:
    start = time.perf_counter()
    out_dir.mkdir(parents=True, exist_ok=True)
    cases = [c for c in CASES if (c.quick or not quick) and (not names or c.name in names)]
    checks, records = run_cases(cases, lambda case: run_case(binary, case), lambda case: case.text())
    seconds = time.perf_counter() - start
    return SuiteResult("The penalty method: convergence to INTERNODES and exact interfaces in series (gate)", checks,
                       [], report_text(cases, checks, records, quick, seconds),
                       {"quick": quick, "seconds": seconds, "cases": json_safe(records)})


def main() -> int:
    return standalone(__doc__, {c.name for c in CASES}, run_suite, "penalty_suite.json", BUILD, binary=True)


if __name__ == "__main__":
    sys.exit(main())
