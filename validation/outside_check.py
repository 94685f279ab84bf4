#!/usr/bin/python3
"""Outside check: the contact solver on meshes and approaches that no suite was tuned on.

The question: does ``converged`` ever come with a wrong answer? A half-disc (2D) and a
hemisphere (3D) of E = 1000 pressed onto a block 1e4 times stiffer, with ``primary = "auto"``, at
contact-zone spacings, block ratios and approaches that the sweep does not use (h_c R/25, R/40,
R/60 in 3D and R/30, R/120, R/400 in 2D; block spacing 1, 2 and 0.7 times the curved body's;
two approaches each, the refinement radius following the contact zone). Each run's force on the
curved body is compared with dolfinx's rigid-flat solution of the same curved mesh
(``contact_reference.py``, exact node-to-plane constraint).

Verdict per run: ``right`` (vouched for by the solver: converged with a passing accuracy report,
and the force within 1% of dolfinx), ``named`` (a status other than converged, or converged with a
failed accuracy indicator; the force error of its last iterate is listed, for information),
``WRONG`` (vouched for, force off by more than 1%: the defect the two reports exist to prevent).
Exits 1 if any run is WRONG or fails to run.

Not part of ``make validate`` (about 15 minutes). Writes ``validation/report/outside_check.md``.

Usage:  /usr/bin/python3 validation/outside_check.py [--binary PATH]
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import subprocess
import sys
from pathlib import Path

VALIDATION = Path(__file__).resolve().parent

import contact_reference  # noqa: E402
import rigid_flat  # noqa: E402
from suite import MeshFailed, failed_report_names, mesh_geo, run_solve, vouched  # noqa: E402

BUILD = VALIDATION / "build" / "outside_check"
REPORT = VALIDATION / "report" / "outside_check.md"
FORCE_TOLERANCE = 0.01
# (dimension, geo script, contact-zone spacings h_c, approaches); block ratios for both.
FAMILIES = ((3, "hemisphere_on_block", (1 / 25, 1 / 40, 1 / 60), (0.004, 0.012)),
            (2, "half_disc_on_block", (1 / 30, 1 / 120, 1 / 400), (0.004, 0.03)))
BLOCK_RATIOS = (1, 2, 0.7)
CURVED = {2: "disc", 3: "sphere"}  # rigid_flat's curved body


def geo_parameters(dim: int, h_c: float, block_ratio: float, delta: float) -> dict:
    """The refined zone follows the contact zone of the approach (a ~ sqrt(R delta) in 3D)."""
    r_c = 2.2 * math.sqrt(2 * delta) if dim == 3 else 2.5 * math.sqrt(delta)
    parameters = {"h_c": round(h_c, 6), "r_c": round(min(max(r_c, 3 * h_c), 0.6), 4), "h_far": 0.4,
                  "block_ratio": block_ratio}
    if dim == 3:
        parameters["d_far"] = 1.5
    return parameters


def case_text(msh: Path, dim: int, delta: float, output: Path) -> str:
    """rigid_flat's case (curved body on the stiff block) with primary "auto" and approach ``delta``."""
    return rigid_flat.case_text(msh, dim, "auto", output, 1.0, delta)


def run(binary: Path, dim: int, geo: str, h_c: float, block_ratio: float, delta: float) -> dict:
    parameters = geo_parameters(dim, h_c, block_ratio, delta)
    name = f"{geo}_" + "_".join(f"{k}{v}" for k, v in parameters.items()) + f"_delta{delta}"
    row = {"dim": dim, "h_c": f"R/{1 / h_c:.0f}", "block_ratio": block_ratio, "delta": delta}
    msh = mesh_geo(geo, dim, parameters, BUILD / "meshes" / f"{name}.msh")
    reference = contact_reference.run_reference(msh, BUILD / "references" / name, delta=delta,
                                                fractions=(1.0,), kappas=())
    output = BUILD / "runs" / name
    case = BUILD / "runs" / f"{name}.toml"
    case.parent.mkdir(parents=True, exist_ok=True)
    case.write_text(case_text(msh, dim, delta, output))
    run_solve(binary, case, output)
    contact = json.loads((output / "summary.json").read_text())["contact"]
    curved = CURVED[dim]
    force = abs(contact["force_primary" if contact["primary"] == curved else "force_secondary"][dim - 1])
    error = force / reference["solution"]["force"] - 1
    verdict = ("right" if abs(error) <= FORCE_TOLERANCE else "WRONG") if vouched(contact) else "named"
    failed = failed_report_names(contact)
    return row | {"primary": contact["primary"], "status": contact["status"], "force_error": error,
                  "failed_checks": failed, "verdict": verdict, "reason": contact["primary_choice"]["reason"]}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", type=Path, default=VALIDATION.parent / "target" / "release" / "internodes")
    args = parser.parse_args()
    commit = subprocess.run(["git", "-C", str(VALIDATION), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    rows = []
    for dim, geo, spacings, approaches in FAMILIES:
        for h_c, block_ratio, delta in itertools.product(spacings, BLOCK_RATIOS, approaches):
            try:
                row = run(args.binary, dim, geo, h_c, block_ratio, delta)
            except (MeshFailed, contact_reference.ReferenceFailure, OSError, KeyError, ValueError,
                    RuntimeError) as error:
                row = {"dim": dim, "h_c": f"R/{1 / h_c:.0f}", "block_ratio": block_ratio, "delta": delta,
                       "verdict": "FAILED", "status": f"{type(error).__name__}: {error}"}
            rows.append(row)
            print(f"{row['verdict']:6s} {dim}D h_c {row['h_c']} block ratio {block_ratio} delta {delta}: "
                  f"{row.get('status')}, primary {row.get('primary')}, force {row.get('force_error', math.nan):+.4f}"
                  f" {row.get('failed_checks', '')}", flush=True)
    counts = {v: sum(r["verdict"] == v for r in rows) for v in ("right", "named", "WRONG", "FAILED")}
    lines = [
        "# Outside check: meshes and approaches no suite was tuned on",
        "",
        f"Written by `validation/outside_check.py` at commit {commit}; do not edit by hand. Curved body "
        "(E = 1000) on a block 1e4 times stiffer, `primary = \"auto\"`, force on the curved body against "
        "dolfinx's rigid flat on the same curved mesh (tolerance 1%).",
        "",
        f"**{len(rows)} runs: {counts['right']} vouched for and right, {counts['named']} ended with a named "
        f"status or a failed accuracy indicator, {counts['WRONG']} vouched for and wrong, {counts['FAILED']} "
        "failed to run.** A named run with a small force error is a right answer the solver could not vouch for.",
        "",
        "| dim | h_c | block ratio | delta | verdict | status | primary | force error | failed checks |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(f"| {r['dim']}D | {r['h_c']} | {r['block_ratio']} | {r['delta']} | {r['verdict']} | "
                     f"{r.get('status')} | {r.get('primary', '')} | {r.get('force_error', math.nan):+.2%} | "
                     f"{', '.join(r.get('failed_checks', []))} |")
    REPORT.write_text("\n".join(lines) + "\n")
    print(f"{counts}; report: {REPORT}")
    return 1 if counts["WRONG"] or counts["FAILED"] else 0


if __name__ == "__main__":
    sys.exit(main())
