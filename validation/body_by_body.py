#!/usr/bin/python3
"""Cross-check with FEniCSx, body by body.

internodes solves a two-body contact problem; its output holds, for each
body k, the displacement u_k, the cell stresses and the nodal contact
traction t_k on the body's candidate surface G_k (``/fields/contact_traction``:
lambda on the primary body, lambda_2 = -R21 lambda on the secondary, zero at
inactive nodes). The coupled system makes each body satisfy

    K_k u_k = f_k + M_k t_k     (free dofs; u_k = g_k on the Dirichlet dofs),

with M_k the lumped P1 surface mass matrix of G_k: the contact force on a
node is A_a t_a, A_a = int_{G_k} phi_a ds its area (the interface mass of
internodes is lumped, so that the pressure its active-set test reads is the
nodal multiplier).

This suite takes those tractions and, for each body **alone**, solves in
dolfinx (``dolfinx_reference.py``: same ``.msh`` file, same material, same
Dirichlet data, nothing else from internodes) the linear elasticity problem
with the nodal loads A_a t_a added to the right-hand side, A_a the row sums
of the P1 surface mass matrix that dolfinx assembles for G_k. Then it compares node by node and
cell by cell:

* ``displacement``: max |u - u_ref| / max |u_ref| over the body's nodes;
* ``stress``: max over cells and components |sigma - sigma_ref| / max |sigma_ref|;
* ``reactions``: max |R - R_ref| / max |R_ref| over the Dirichlet groups;
* ``contact force``: |F - F_ref| / |F_ref|, F the total contact force of the
  body in ``summary.json`` and F_ref the sum of dolfinx's contact load vector
  (no linear solve: round-off only, tolerance 1e-12);
* ``status``: 0 if the contact solve converged, 1 otherwise (tolerance 0).

Agreement to 1e-8 (observed: round-off) shows that each body's field is the
exact discrete elastic solution for the tractions internodes reports: the
contact iteration adds nothing to the bodies but these surface loads.

Run alone:  /usr/bin/python3 validation/body_by_body.py [--quick] [--binary PATH]
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import sys
import time
import tomllib
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np
from dolfinx import fem

VALIDATION = Path(__file__).resolve().parent
REPO = VALIDATION.parent

from compare import ERRORS, Check, InternodesOutput, cell_order, failure, pad3, reaction_check, relative_max  # noqa: E402
from dolfinx_reference import Body, ReferenceFailure, ReferenceModel, read_case  # noqa: E402
from suite import MeshFailed, SuiteResult, contact_sides, mesh_geo, run_solve, toml_text  # noqa: E402

BUILD = VALIDATION / "build" / "body_by_body"
# Fields go through one linear solve on each side: round-off times cond(K_FF).
FIELD_TOLERANCE = 1e-8
# The contact force is a sum of the same surface-mass products: round-off only.
FORCE_TOLERANCE = 1e-12
FORMULATIONS = ("frictionless", "tied")


@dataclass(frozen=True)
class ContactCase:
    """A geo script meshed with some parameters, and the case file whose bodies and contact it uses."""

    name: str
    geo: str  # geo/<geo>.geo
    dim: int
    parameters: dict
    template: str  # geo/<template>.toml: bodies, supports, contact surfaces
    quick: bool = False  # also in the quick run (make test)

    def description(self) -> str:
        return f"{self.geo}.geo, " + ", ".join(f"{k} = {v}" for k, v in self.parameters.items())


CASES = (
    ContactCase("half_disc_2d", "half_disc_on_block", 2, {"h_c": 0.0125, "r_c": 0.2, "h_far": 0.5},
                "half_disc_on_block", quick=True),
    ContactCase("hemisphere_hc0.03", "hemisphere_on_block", 3, {"h_c": 0.03, "r_c": 0.2}, "hemisphere_on_block",
                quick=True),
    ContactCase("hemisphere_hc0.015", "hemisphere_on_block", 3,
                {"h_c": 0.015, "r_c": 0.16, "h_far": 0.5, "d_far": 1.0}, "hemisphere_on_block"),
)


class StepFailed(RuntimeError):
    """Meshing or the internodes solve failed; the message says which and why."""


# ---------------------------------------------------------------------------
# Case files
# ---------------------------------------------------------------------------


def write_cases(case: ContactCase, formulation: str, mesh: Path, folder: Path) -> tuple[Path, Path, dict]:
    """The internodes case file (template with this mesh and formulation) and its bodies-only twin.

    ``dolfinx_reference.read_case`` reads only ``mesh`` and ``[[body]]``: the
    twin holds exactly the same bodies, so both codes see the same supports
    and materials. Returns (case file, bodies file, the [contact] table).
    """
    with open(REPO / "geo" / f"{case.template}.toml", "rb") as f:
        data = tomllib.load(f)
    data.pop("geo_parameters", None)
    data["mesh"] = str(mesh)
    data["output"] = str(folder / "internodes")
    data["contact"] = data["contact"] | {"formulation": formulation}
    folder.mkdir(parents=True, exist_ok=True)
    case_file, bodies_file = folder / "case.toml", folder / "bodies.toml"
    case_file.write_text(f"# {case.description()}, {formulation} (written by body_by_body.py)\n"
                         + toml_text(data))
    bodies_file.write_text("# the bodies of case.toml, for dolfinx_reference.read_case\n"
                           + toml_text({"mesh": data["mesh"], "body": data["body"]}))
    return case_file, bodies_file, data["contact"]


def generate_mesh(case: ContactCase) -> Path:
    """geo/<geo>.geo with the case's parameters -> build/body_by_body/meshes/<name>.msh (``suite.mesh_geo``)."""
    try:
        return mesh_geo(case.geo, case.dim, case.parameters, BUILD / "meshes" / f"{case.name}.msh")
    except MeshFailed as error:
        raise StepFailed(str(error)) from error


# ---------------------------------------------------------------------------
# dolfinx with the contact tractions as surface loads
# ---------------------------------------------------------------------------


class TractionModel(ReferenceModel):
    """The reference model, with a P1 traction on a body's contact surface added to its loads."""

    def __init__(self, msh_path: Path, node_coordinates: dict[str, np.ndarray]):
        super().__init__(msh_path, node_coordinates)
        self.tractions: dict[str, tuple[str, np.ndarray]] = {}

    def set_traction(self, body: str, group: str, nodal: np.ndarray) -> None:
        """Load ``body`` with the P1 traction of nodal values ``nodal`` (n, 3), internodes local numbering, on ``group``.

        Nodes with a nonzero traction must lie on ``group``: elsewhere the
        ds(group) integral would not see them.
        """
        on_group = np.zeros(len(nodal), bool)
        local = np.full(self.V.dofmap.index_map.size_local, -1)
        local[self.vertex_map(body)] = np.arange(len(nodal))
        vertex_dofs = fem.locate_dofs_topological(self.Q, self.dim - 1, self.facets(group))
        on_group[local[vertex_dofs]] = True
        off = np.flatnonzero((nodal != 0).any(axis=1) & ~on_group)
        if off.size:
            raise ReferenceFailure(f"body '{body}': {off.size} nodes off '{group}' carry a contact traction "
                                   f"(first: local node {off[0]})")
        if (nodal[:, self.dim:] != 0).any():
            raise ReferenceFailure(f"body '{body}': nonzero out-of-plane traction in a 2D run")
        self.tractions[body] = (group, nodal[:, : self.dim])

    def traction_load(self, body: str) -> np.ndarray:
        """The lumped contact load A_a t_a (n * dim,), internodes numbering; A_a = sum_b M[a, b], M the
        group's P1 surface mass assembled by dolfinx."""
        group, nodal = self.tractions[body]
        areas = np.asarray(self.surface_mass(body, group).sum(axis=1)).ravel()
        return (areas[:, None] * nodal).ravel()

    def load_vector(self, body: Body) -> np.ndarray:
        """The case's loads of the body, plus its lumped contact load if a traction is set."""
        f = super().load_vector(body)
        if body.name in self.tractions:
            f = f + self.traction_load(body.name)
        return f

    def contact_force(self, body: str) -> np.ndarray:
        """Total force of the traction, sum_a A_a t_a (dim,)."""
        return self.traction_load(body).reshape(-1, self.dim).sum(axis=0)


def contact_tractions(folder: Path, out: InternodesOutput) -> dict[str, np.ndarray]:
    """/fields/contact_traction (n, 3) of each body, in its local node numbering."""
    path = folder / "solution.h5"
    with h5py.File(path, "r") as h5:
        if "fields/contact_traction" not in h5:
            raise ReferenceFailure(f"{path}: no /fields/contact_traction (not a contact run?)")
        traction = h5["fields/contact_traction"][()]
    return {name: traction[b.summary["node_offset"]: b.summary["node_offset"] + b.summary["num_nodes"]]
            for name, b in out.bodies.items()}


def body_checks(model: TractionModel, out: InternodesOutput, body: Body, summary_force: list[float],
                label: str) -> tuple[list[Check], dict]:
    """Solve ``body`` alone in dolfinx with its contact traction; compare fields, reactions and force."""
    ours = out.body(body.name)
    where = f"{label} {body.name}"
    start = time.perf_counter()
    ref = model.solve(body)
    force_ref = model.contact_force(body.name)
    seconds = time.perf_counter() - start
    u_ref = pad3(ref.displacement)
    stress_ref = ref.stress[cell_order(ours.cells, ref.cells, where)]
    force = np.asarray(summary_force[: model.dim], dtype=float)
    figures = {
        "displacement": relative_max(ours.displacement, u_ref),
        "stress": relative_max(ours.stress, stress_ref),
        "contact force": float(np.linalg.norm(force - force_ref) / np.linalg.norm(force_ref)),
    }
    reactions = reaction_check(ours.summary.get("reactions", {}), ref.reactions, where)
    figures["reactions"] = reactions.figure
    checks = [
        Check("displacement", where, figures["displacement"], FIELD_TOLERANCE,
              f"max|u| = {abs(u_ref).max():.3e}, {len(u_ref)} nodes"),
        Check("stress", where, figures["stress"], FIELD_TOLERANCE,
              f"max|sigma| = {abs(stress_ref).max():.3e}, {len(stress_ref)} cells"),
        reactions,
        Check("contact force", where, figures["contact force"], FORCE_TOLERANCE,
              "|F| = {:.6e}".format(np.linalg.norm(force_ref))),
    ]
    info = {"nodes": len(u_ref), "cells": len(stress_ref), "contact_force": force_ref.tolist(),
            "figures": figures, "dolfinx_seconds": seconds}
    return checks, info


# ---------------------------------------------------------------------------
# One case, one formulation
# ---------------------------------------------------------------------------


def check_case(binary: Path, case: ContactCase, mesh: Path, formulation: str) -> tuple[list[Check], dict]:
    """Solve with internodes, then every body alone with dolfinx; checks and a record for the report."""
    label = f"{case.name} {formulation}"
    folder = BUILD / f"{case.name}_{formulation}"
    case_file, bodies_file, contact = write_cases(case, formulation, mesh, folder)
    output = folder / "internodes"
    shutil.rmtree(output, ignore_errors=True)  # never compare stale output
    start = time.perf_counter()
    solved = run_solve(binary, case_file, output)
    if solved.exit != 0:
        raise StepFailed(f"internodes solve {case_file} failed (exit {solved.exit}): {solved.tail(5)}")
    record = {"case": case.name, "mesh": case.description(), "formulation": formulation,
              "internodes_seconds": time.perf_counter() - start}

    summary = json.loads((output / "summary.json").read_text())["contact"]
    status = summary["status"]
    record |= {"status": status, "iterations": len(summary["iterations"]),
               "active": [summary["active_primary"], summary["active_secondary"]],
               "force_imbalance": summary["force_imbalance"]}
    checks = [Check("status", label, 0 if status == "converged" else 1, 0,
                    f"{status}, {len(summary['iterations'])} iterations, active "
                    f"{summary['active_primary']} + {summary['active_secondary']}")]

    start = time.perf_counter()
    out = InternodesOutput(output)
    bodies = read_case(bodies_file).bodies
    model = TractionModel(mesh, {b.name: out.body(b.name).geometry for b in bodies})
    tractions = contact_tractions(output, out)
    surfaces = contact_sides(contact)
    primary = summary.get("primary", contact.get("primary"))  # as solved (the case may say "auto")
    secondary = next(b for b in surfaces if b != primary)
    sides = {primary: (surfaces[primary], summary["force_primary"]),
             secondary: (surfaces[secondary], summary["force_secondary"])}
    record["bodies"] = {}
    for body in bodies:
        group, force = sides[body.name]
        try:
            model.set_traction(body.name, group, tractions[body.name])
            body_result, info = body_checks(model, out, body, force, label)
            checks += body_result
            record["bodies"][body.name] = info | {"surface": group}
        except ERRORS as error:
            checks.append(failure("body", f"{label} {body.name}", f"{type(error).__name__}: {error}"))
    record["dolfinx_seconds"] = time.perf_counter() - start
    return checks, record


# ---------------------------------------------------------------------------
# The suite
# ---------------------------------------------------------------------------


def report_text(records: list[dict]) -> str:
    """What is compared and why, and one row per case, formulation and body."""
    rows = []
    for r in records:
        for name, b in r.get("bodies", {}).items():
            f = b["figures"]
            rows.append(f"| {r['case']} | {r['formulation']} | {name} | {b['nodes']} | {r['status']}, "
                        f"{r['iterations']} its | {np.linalg.norm(b['contact_force']):.4e} | "
                        f"{f['displacement']:.1e} | {f['stress']:.1e} | {f['reactions']:.1e} | "
                        f"{f['contact force']:.1e} |")
    meshes = sorted({f"`{r['case']}`: {r['mesh']}" for r in records})
    return "\n".join([
        "internodes' converged contact tractions are taken from its output (`/fields/contact_traction`: "
        "lambda on the primary body, lambda_2 = -R21 lambda on the secondary, zero at inactive nodes) "
        "and applied, body by body, as a surface load in dolfinx: the nodal values are interpolated into "
        "a P1 vector function t_h and `inner(t_h, v) ds(contact surface)` is added to the right-hand side "
        "(exact quadrature), which is the load `M t` that the coupled system applies to that body. Each body "
        "is then solved **alone** (same `.msh`, same material, same Dirichlet data, nothing else from "
        "internodes), and its displacements (node by node), cell stresses (cell by cell) and support "
        "reactions are compared with internodes'. Agreement to 1e-8 relative (observed: round-off) shows "
        "that each body's field is the exact discrete elastic solution for the tractions internodes reports: "
        "the contact coupling acts on the bodies through these surface loads and nothing else. "
        "`contact force` compares the total force of t_h assembled by dolfinx with the force in `summary.json` "
        "(no solve: round-off only).",
        "",
        "Meshes: " + "; ".join(meshes) + ".",
        "",
        "| case | formulation | body | nodes | internodes status | \\|F\\| | displacement | stress | reactions "
        "| contact force |",
        "|---|---|---|---|---|---|---|---|---|---|",
        *rows,
    ])


def run_suite(binary: Path, quick: bool, out_dir: Path) -> SuiteResult:
    """Every case of ``CASES`` (quick: those marked quick) with both formulations; see the module doc."""
    out_dir.mkdir(parents=True, exist_ok=True)
    result = SuiteResult("Body by body: each body's field is an elastic solution for our contact tractions")
    records = []
    for case in (c for c in CASES if c.quick or not quick):
        try:
            mesh = generate_mesh(case)
        except (StepFailed, OSError) as error:
            result.checks.append(failure("mesh", case.name, str(error)))
            continue
        for formulation in FORMULATIONS:
            label = f"{case.name} {formulation}"
            try:
                checks, record = check_case(binary, case, mesh, formulation)
            except (StepFailed, *ERRORS) as error:
                result.checks.append(failure("run", label, f"{type(error).__name__}: {error}"))
                continue
            result.checks += checks
            records.append(record)
    result.text = report_text(records)
    result.data = {"cases": records}
    return result


def main() -> int:
    """Run the suite alone: print the checks and the report text; 0 if every check passes."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--binary", type=Path, default=REPO / "target/release/internodes",
                        help="internodes executable (default: target/release/internodes)")
    parser.add_argument("--quick", action="store_true", help="2D half-disc and coarse hemisphere only")
    parser.add_argument("--out-dir", type=Path, default=BUILD / "report", help="the suite's report folder")
    args = parser.parse_args()
    from run import print_table  # here, not at the top: run.py may import this module

    start = time.perf_counter()
    result = run_suite(args.binary, args.quick, args.out_dir)
    print(result.text)
    print()
    print_table(result.checks)
    passed = bool(result.checks) and all(c.passed for c in result.checks)
    failed = sum(not c.passed for c in result.checks)
    print(f"\n{result.title}: {len(result.checks) - failed} passed, {failed} failed, "
          f"{time.perf_counter() - start:.1f} s")
    (args.out_dir / "results.json").write_text(json.dumps(
        {"passed": passed, "data": result.data,
         "checks": [vars(c) | {"figure": None if math.isnan(c.figure) else c.figure, "passed": c.passed}
                    for c in result.checks]}, indent=2))
    return 0 if passed else 1


if __name__ == "__main__":
    sys.exit(main())
