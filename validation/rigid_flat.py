#!/usr/bin/python3
"""Report suite: internodes against an independent dolfinx contact reference.

The half-disc (2D) and the hemisphere (3D) of ``geo/half_disc_on_block.geo`` and
``geo/hemisphere_on_block.geo`` are pressed onto a rigid flat and solved by dolfinx with PETSc's
variational-inequality Newton method (``contact_reference.py``, which owes nothing to our code).
internodes solves the same mesh with the block 1e4 times stiffer than the curved body (E = 1e7
against 1e3), twice: with the stiff block as the primary body (a choice the solver must survive) and with the
curved body as the primary.

For the stiff-block-primary runs the block is meshed BLOCK_RATIO = 2 times coarser than the curved
body (``block_ratio`` of the geo scripts; the curved-primary runs keep 1): the coarser contact
surface carries the multiplier, as ``primary = "auto"`` would choose (`docs/method.md` 3.6). A multiplier
mesh coarser than the mesh it constrains is the classical inf-sup-stable choice; with a nearly
rigid primary as fine as the secondary the multiplier has modes that nothing controls (the sweep
has such cases: they must be right or end with a named failure).

Both runs are solved at the reference's approach fractions (0.25, 0.5, 0.75, 1; one solve each
from the reference configuration), so the force-approach curve is compared point by point with
dolfinx on the same geometry; Hertz's half-space law is shown beside it (3D) with the size of the
geometry effect.

Targets: contact force within 1% of the reference (at full approach and along the force-approach
curve), contact radius (largest radius of a node in contact) within one interface spacing.
Pressure profiles are overlaid in the figures.

Usage:  /usr/bin/python3 validation/rigid_flat.py [--quick] [--binary PATH]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

VALIDATION = Path(__file__).resolve().parent
REPO = VALIDATION.parent

import contact_reference  # noqa: E402
import rigid_flat_comparison  # noqa: E402
from compare import Check  # noqa: E402
from suite import Figure, SuiteResult, body_table, case_toml, contact_table, mesh_geo, run_solve  # noqa: E402

BUILD = VALIDATION / "build" / "rigid_flat"
STIFFNESS_RATIO = 1e4
YOUNGS_MODULUS = 1000.0
BLOCK_RATIO = 2
APPROACHES = contact_reference.DEFAULT_FRACTIONS

# label: (geo script, gmsh dimension, geo parameters, also in the quick run). Each run meshes the
# block with its role's block ratio (below).
MESHES = {
    "2D half-disc, R/80": ("half_disc_on_block", 2, {"h_c": 0.0125, "r_c": 0.2, "h_far": 0.5}, True),
    "3D hemisphere, R/33": ("hemisphere_on_block", 3, {"h_c": 0.03, "r_c": 0.2}, True),
    "3D hemisphere, R/67": ("hemisphere_on_block", 3, {"h_c": 0.015, "r_c": 0.16, "h_far": 0.5, "d_far": 1.0}, False),
}
# The curved body and its top (pushed down by the full approach), per dimension.
BODIES = {2: {"curved": "disc", "top": "disc_top"}, 3: {"curved": "sphere", "top": "sphere_top"}}
#: The full approach: the curved body's top moves down by it, the block's base is clamped.
APPROACH = {2: 0.02, 3: 0.01}


def mesh(script: str, dim: int, parameters: dict) -> Path:
    """gmsh the geo script with the parameters into build/ (cached)."""
    name = script + "".join(f"_{k}{v}" for k, v in parameters.items()) + ".msh"
    return mesh_geo(script, dim, parameters, BUILD / name)


def case_text(msh: Path, dim: int, primary: str, output: Path, fraction: float, approach: float | None = None,
              listed_first: str | None = None) -> str:
    """Our case: the curved body (E = 1e3) on a block 1e4 times stiffer, ``primary`` (a body, or "auto")
    carrying lambda, at ``fraction`` of the ``approach`` (default the full one, ``APPROACH``) in one load
    step from the reference configuration. The contact bodies are listed ``listed_first`` first (default:
    the primary, or the curved body under "auto")."""
    curved, top = BODIES[dim]["curved"], BODIES[dim]["top"]
    first = listed_first or (curved if primary == "auto" else primary)
    second = "block" if first == curved else curved
    contact = contact_table((first, second), (f"{first}_contact", f"{second}_contact"), primary,
                            load_steps=[fraction])
    components = ["ux", "uy", "uz"][:dim]
    zero = dict.fromkeys(components, 0.0)
    push = zero | {components[-1]: -(APPROACH[dim] if approach is None else approach)}
    bodies = [body_table(curved, YOUNGS_MODULUS, 0.3, [(top, push)]),
              body_table("block", YOUNGS_MODULUS * STIFFNESS_RATIO, 0.3, [("block_base", zero)])]
    return case_toml(msh, output, contact, bodies)


def run_suite(binary: Path, quick: bool, out_dir: Path) -> SuiteResult:
    """Reference and internodes runs on every mesh; checks, overlays and a table."""
    out_dir.mkdir(parents=True, exist_ok=True)
    result = SuiteResult(title="Independent dolfinx contact reference: a rigid flat")
    rows = []
    for label, (script, dim, parameters, in_quick) in MESHES.items():
        if quick and not in_quick:
            continue
        slug = label.replace(" ", "_").replace(",", "").replace("/", "-")
        entry = {"mesh": label, "runs": {}}
        for primary in (BODIES[dim]["curved"], "block"):
            role = "stiff block primary" if primary == "block" else f"{primary} primary"
            name = f"{label}, {role}"
            block_ratio = BLOCK_RATIO if primary == "block" else 1
            msh = mesh(script, dim, parameters | {"block_ratio": block_ratio})
            run_dir = BUILD / slug / f"block_ratio_{block_ratio}"
            reference = contact_reference.run_reference(msh, run_dir / "reference", kappas=(1e3, 1e5))
            reference_json = run_dir / "reference" / "contact_reference.json"
            if block_ratio == 1:
                result.figures.append(Figure(f"{label}: dolfinx reference pressure against Hertz",
                                             _copy(Path(reference["plots"]["pressure"]),
                                                   out_dir / f"{slug}_reference.png")))
            # One solve per approach, each from the reference configuration; the last is the full one.
            folders = {}
            for fraction in APPROACHES:
                folders[fraction] = run_dir / f"{primary}_{fraction:g}"
                case = run_dir / f"{primary}_{fraction:g}.toml"
                case.write_text(case_text(msh, dim, primary, folders[fraction], fraction))
                run_solve(binary, case, folders[fraction])
            try:
                checks = rigid_flat_comparison.compare_with_internodes(reference_json, folders[1.0],
                                                                   out_dir / f"{slug}_{primary}_overlay.png")
            except (contact_reference.ReferenceFailure, OSError, KeyError) as error:
                result.checks.append(Check("rigid flat: run", name, float("nan"), 0.0, str(error)))
                continue
            result.figures.append(Figure(f"{name}: pressure of internodes and dolfinx", Path(checks["plot"])))
            curve = force_approach(reference, folders, primary == BODIES[dim]["curved"], dim)
            worst = max(abs(c["relative_difference"]) for c in curve)
            unconverged = [f"{c['delta']:.3g}" for c in curve if c["status"] != "converged"]
            status_ok = checks["status"] == "converged"
            result.checks += [
                Check("rigid flat: status", name, 0.0 if status_ok else 1.0, 0.0, checks["status"]),
                Check("rigid flat: force", name, checks["force"]["relative_difference"], 0.01,
                      f"P = {checks['force']['internodes']:.5g}, reference {checks['force']['reference']:.5g}"),
                Check("rigid flat: radius / h", name, checks["contact_radius"]["difference_in_h"], 1.0,
                      f"a = {checks['contact_radius']['internodes_a_nodes']:.4g}, "
                      f"reference {checks['contact_radius']['reference_a_nodes']:.4g}"),
                Check("rigid flat: force-approach", name, worst, 0.01,
                      "largest force difference over approaches "
                      + ", ".join(f"{c['delta']:.3g}" for c in curve)
                      + (f"; not converged at {', '.join(unconverged)}" if unconverged else "")),
            ]
            entry["runs"][role] = {k: checks[k] for k in ("status", "iterations", "force", "contact_radius",
                                                          "pressure")}
            entry["runs"][role] |= {
                "block_ratio": block_ratio, "h": reference["solution"]["interface_spacing"]["h"],
                "force_approach": curve,
                "reference_force_approach": [{k: s[k] for k in ("delta", "force", "hertz_force_for_delta")}
                                             for s in reference["force_approach"]]}
            rows.append((name, checks))
        if not entry["runs"]:
            continue
        entry["geometry_effect"] = geometry_effect(next(iter(entry["runs"].values()))["reference_force_approach"])
        figure = out_dir / f"{slug}_force_approach.png"
        plot_force_approach(label, entry, dim, figure)
        result.figures.append(Figure(f"{label}: force against approach, internodes and dolfinx", figure))
        result.data[label] = entry
    result.text = _text(rows, result.data)
    return result


def force_approach(reference: dict, folders: dict, curved_is_primary: bool, dim: int) -> list[dict]:
    """Our contact force on the curved body at each approach against the reference at the same one.

    A solve that did not converge (or wrote nothing) is kept with its status and the force of its
    last iterate (NaN if none): the figure then fails the target instead of disappearing.
    """
    reference_by_fraction = {round(s["fraction"], 12): s for s in reference["force_approach"]}
    key = "force_primary" if curved_is_primary else "force_secondary"
    curve = []
    for fraction, folder in sorted(folders.items()):
        ref = reference_by_fraction[round(fraction, 12)]
        try:
            contact = json.loads((folder / "summary.json").read_text())["contact"]
            status, force = contact["status"], float(contact[key][dim - 1])
        except (OSError, KeyError, json.JSONDecodeError):
            status, force = "no output", math.nan
        difference = (force - ref["force"]) / ref["force"]
        curve.append({"delta": ref["delta"], "status": status, "force": force, "reference": ref["force"],
                      "relative_difference": difference if math.isfinite(difference) else math.inf})
    return curve


def geometry_effect(reference_curve: list[dict]) -> float | None:
    """Largest relative difference of Hertz's half-space force (3D) from the reference's, finite body."""
    rows = [r for r in reference_curve if r["hertz_force_for_delta"] is not None]
    if not rows:
        return None
    return max(abs(r["hertz_force_for_delta"] - r["force"]) / r["force"] for r in rows)


def plot_force_approach(label: str, entry: dict, dim: int, path: Path) -> None:
    """P(delta): dolfinx reference, both internodes runs, and Hertz's law (3D, for information)."""
    plt = contact_reference._pyplot()
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for (role, run), marker, color in zip(entry["runs"].items(), ("s", "^"), ("tab:orange", "tab:green")):
        ref = run["reference_force_approach"]
        ax.plot([0.0] + [r["delta"] for r in ref], [0.0] + [r["force"] for r in ref], "-", color=color, lw=1,
                label=f"dolfinx VI, rigid flat (mesh of the {role} run)")
        done = [c for c in run["force_approach"] if c["status"] == "converged"]
        ax.plot([c["delta"] for c in done], [c["force"] for c in done], marker, color=color, mfc="none", ms=9,
                label=f"internodes, {role}, block ratio {run['block_ratio']}")
        failed = [c for c in run["force_approach"] if c["status"] != "converged"]
        if failed:
            ax.plot([c["delta"] for c in failed], [c["force"] for c in failed], "x", color=color, ms=9,
                    label=f"internodes, {role}: not converged (last iterate)")
    ref = next(iter(entry["runs"].values()))["reference_force_approach"]
    d = [0.0] + [r["delta"] for r in ref]
    if dim == 3 and entry.get("geometry_effect") is not None:
        ax.plot(d, [0.0] + [r["hertz_force_for_delta"] for r in ref], "k--", lw=1,
                label=f"Hertz half-space law (differs by up to {entry['geometry_effect']:.1%})")
    contact_reference.finish_force_approach_plot(fig, ax, f"{label}: force against approach", dim, path)


def _copy(source: Path, target: Path) -> Path:
    target.write_bytes(source.read_bytes())
    return target


def _text(rows, data: dict) -> str:
    lines = [
        "The curved body alone is pressed onto a rigid flat by dolfinx (PETSc `vinewtonrsls`, exact "
        "node-to-plane constraint, certified by its KKT conditions and a penalty sequence converging to "
        f"it); internodes solves the same mesh with the block {STIFFNESS_RATIO:.0e} times stiffer; for the "
        f"stiff-block-primary runs the block is meshed {BLOCK_RATIO} times coarser than the curved body "
        "(see below) and dolfinx solves that mesh too. Force: relative difference of the contact force on "
        "the curved body at full approach; force-approach: the largest such difference over the approaches "
        f"{', '.join(f'{s:g}' for s in APPROACHES)} of the full one, each solved from the reference "
        "configuration; radius: "
        "difference of the largest radius of a node in contact, in interface spacings; imbalance: "
        "|force on the primary + force on the secondary| / |force on the primary|.",
        "",
        "| run | status | iterations | force (ours / ref) | force diff. | force-approach diff. | radius diff. / h "
        "| imbalance | largest nodal pressure difference / p_max |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, c in rows:
        f, a, p = c["force"], c["contact_radius"], c["pressure"]
        label, role = name.rsplit(", ", 1)
        curve = data[label]["runs"][role].get("force_approach", [])
        worst = max((abs(x["relative_difference"]) for x in curve), default=math.nan)
        lines.append(f"| {name} | {c['status']} | {c['iterations']} | {f['internodes']:.5g} / {f['reference']:.5g} "
                     f"| {f['relative_difference']:.2%} | {worst:.2%} | {a['difference_in_h']:.2f} "
                     f"| {f['internodes_force_imbalance']:.2%} | {p['max_lambda_difference_over_p_max']:.2f} |")
    effects = [(label, entry["geometry_effect"]) for label, entry in data.items()
               if entry.get("geometry_effect") is not None]
    if effects:
        lines += ["", "Geometry effect: Hertz's half-space force for the same approach differs from the dolfinx "
                  "reference on the finite body by up to "
                  + "; ".join(f"{e:.1%} ({label})" for label, e in effects)
                  + ". That is why the force-approach curve is tested against dolfinx, not against Hertz. "
                  "In 2D the approach-load relation depends on the body's size and supports and has no "
                  "closed form; only the dolfinx curve is shown."]
    lines += [
        "",
        "Choosing the primary. The stiff block runs are meshed "
        f"{BLOCK_RATIO} times coarser, the configuration `primary = \"auto\"` picks (the coarser contact "
        "surface carries the multiplier: docs/method.md 3.6). The force on the curved body is the one "
        "compared.",
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
    return 0 if all(c.passed for c in result.checks) else 1


if __name__ == "__main__":
    sys.exit(main())
