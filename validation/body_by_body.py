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
  (no linear solve: round-off only, tolerance 1e-12; with several pairs over
  the sum of the pairs' |F|);
* ``status``: 0 if the contact solve converged, 1 otherwise (tolerance 0).

Agreement to 1e-8 (observed: round-off) shows that each body's field is the
exact discrete elastic solution for the tractions internodes reports: the
contact iteration adds nothing to the bodies but these surface loads.

Several contact pairs (``[[contact]]``): a body in several pairs is loaded on
each of its contact surfaces, and its contact forces are compared relative to
the sum of their magnitudes (a block between two others carries a net contact
force of nothing). A force-controlled group (``[[body.force]]``) is held by
dolfinx at the displacement internodes found for it, so its reaction must be
the force (``reactions``). A body whose supports leave it free to move (held
by its contacts alone) has the free dofs of dim far-apart nodes pinned at
internodes' displacement: internodes' answer puts no force on them, so their
reaction in dolfinx (``pinned reaction``) is how far its contact forces
balance its loads, over the sum of their magnitudes.

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
from dolfinx_reference import Body, ReferenceFailure, ReferenceModel, read_case, rigid_body_modes  # noqa: E402
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
    formulations: tuple[str, ...] = FORMULATIONS  # each solved in turn

    def description(self) -> str:
        return f"{self.geo}.geo, " + ", ".join(f"{k} = {v}" for k, v in self.parameters.items())


CASES = (
    ContactCase("half_disc_2d", "half_disc_on_block", 2, {"h_c": 0.0125, "r_c": 0.2, "h_far": 0.5},
                "half_disc_on_block", quick=True),
    ContactCase("hemisphere_hc0.03", "hemisphere_on_block", 3, {"h_c": 0.03, "r_c": 0.2}, "hemisphere_on_block",
                quick=True),
    ContactCase("hemisphere_hc0.015", "hemisphere_on_block", 3,
                {"h_c": 0.015, "r_c": 0.16, "h_far": 0.5, "d_far": 1.0}, "hemisphere_on_block"),
    # Several pairs (the templates' own formulation): a block held only by its two contacts; a
    # disc and a ball held only by theirs, between plates of which the upper is pressed by a force.
    ContactCase("three_blocks_2d", "three_blocks_2d", 2, {}, "three_blocks_2d", quick=True,
                formulations=("frictionless",)),
    ContactCase("disc_between_plates_2d", "disc_between_plates_2d", 2, {}, "disc_between_plates_2d", quick=True,
                formulations=("frictionless",)),
    ContactCase("ball_between_plates_3d", "ball_between_plates_3d", 3, {"h_c": 0.015, "r_c": 0.16},
                "ball_between_plates_3d", formulations=("frictionless",)),
)


class StepFailed(RuntimeError):
    """Meshing or the internodes solve failed; the message says which and why."""


# ---------------------------------------------------------------------------
# Case files
# ---------------------------------------------------------------------------


def write_case(case: ContactCase, formulation: str, mesh: Path, folder: Path) -> tuple[Path, dict, list[dict]]:
    """The internodes case file: the template with this mesh and formulation (in every pair).

    Returns (case file, the template's data, its contact tables: one for a `[contact]` table,
    one per pair for `[[contact]]` tables).
    """
    with open(REPO / "geo" / f"{case.template}.toml", "rb") as f:
        data = tomllib.load(f)
    data.pop("geo_parameters", None)
    data["mesh"] = str(mesh)
    data["output"] = str(folder / "internodes")
    tables = data["contact"] if isinstance(data["contact"], list) else [data["contact"]]
    tables = [t | {"formulation": formulation} for t in tables]
    data["contact"] = tables if isinstance(data["contact"], list) else tables[0]
    folder.mkdir(parents=True, exist_ok=True)
    case_file = folder / "case.toml"
    case_file.write_text(f"# {case.description()}, {formulation} (written by body_by_body.py)\n"
                         + toml_text(data))
    return case_file, data, tables


def write_bodies(data: dict, forced: list[dict], folder: Path) -> Path:
    """The bodies of the case file, for ``dolfinx_reference.read_case`` (which reads only ``mesh``
    and ``[[body]]``: both codes see the same supports and materials), each force-controlled group
    turned into a Dirichlet condition at the displacement internodes found for it (``forced``: the
    last step's records), so that dolfinx solves the same body with the group where the force put
    it; its reaction must then be the force."""
    bodies = []
    for body in data["body"]:
        body = {k: v for k, v in body.items() if k != "force"}
        dirichlet = [dict(d) for d in body.get("dirichlet", [])]
        for record in (r for r in forced if r["body"] == body["name"]):
            key = f"u{record['component']}"
            entry = next((d for d in dirichlet if d["group"] == record["group"]), None)
            if entry is None:
                entry = {"group": record["group"]}
                dirichlet.append(entry)
            entry[key] = record["displacement"]
        bodies.append(body | {"dirichlet": dirichlet})
    path = folder / "bodies.toml"
    path.write_text("# the bodies of case.toml, force-controlled groups at their displacement, for "
                    "dolfinx_reference.read_case\n" + toml_text({"mesh": data["mesh"], "body": bodies}))
    return path


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
        self.tractions: dict[str, tuple[list[str], np.ndarray]] = {}

    def set_traction(self, body: str, groups: list[str], nodal: np.ndarray) -> None:
        """Load ``body`` with the P1 traction of nodal values ``nodal`` (n, 3), internodes local numbering, on
        its contact surfaces ``groups`` (one per pair the body is in).

        Nodes with a nonzero traction must lie on one of ``groups``: elsewhere
        the ds(group) integrals would not see them.
        """
        on_group = np.zeros(len(nodal), bool)
        local = np.full(self.V.dofmap.index_map.size_local, -1)
        local[self.vertex_map(body)] = np.arange(len(nodal))
        for group in groups:
            vertex_dofs = fem.locate_dofs_topological(self.Q, self.dim - 1, self.facets(group))
            on_group[local[vertex_dofs]] = True
        off = np.flatnonzero((nodal != 0).any(axis=1) & ~on_group)
        if off.size:
            raise ReferenceFailure(f"body '{body}': {off.size} nodes off {groups} carry a contact traction "
                                   f"(first: local node {off[0]})")
        if (nodal[:, self.dim:] != 0).any():
            raise ReferenceFailure(f"body '{body}': nonzero out-of-plane traction in a 2D run")
        self.tractions[body] = (groups, nodal[:, : self.dim])

    def traction_load(self, body: str) -> np.ndarray:
        """The lumped contact load A_a t_a (n * dim,), internodes numbering; A_a = sum_b M[a, b], M the
        P1 surface mass of the body's contact surfaces assembled by dolfinx."""
        groups, nodal = self.tractions[body]
        areas = sum(np.asarray(self.surface_mass(body, group).sum(axis=1)).ravel() for group in groups)
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


def pins(model: TractionModel, body: Body, x: np.ndarray, u: np.ndarray) -> dict[int, float]:
    """For a body whose Dirichlet groups leave rigid motions free (held by its contacts alone), the
    free dofs of dim far-apart nodes (the farthest from the centroid, the farthest from it, in 3D
    the farthest from the line of the two) at internodes' displacement ``u`` (n, dim): dolfinx then
    solves the same body with no free motion, and the reactions of these dofs measure how far
    internodes' contact forces balance the body's loads. Empty for a body its supports hold."""
    dim = model.dim
    constrained = np.concatenate([dofs for group in model.dirichlet_dofs(body).values()
                                  for dofs in group.values()] or [np.zeros(0, int)]).astype(int)
    modes = rigid_body_modes(x[:, :dim])
    if np.linalg.matrix_rank(modes[constrained]) == modes.shape[1]:
        return {}
    first = int(np.linalg.norm(x - x.mean(axis=0), axis=1).argmax())
    second = int(np.linalg.norm(x - x[first], axis=1).argmax())
    nodes = [first, second]
    if dim == 3:
        axis = (x[second] - x[first]) / np.linalg.norm(x[second] - x[first])
        offset = x - x[first]
        nodes.append(int(np.linalg.norm(offset - np.outer(offset @ axis, axis), axis=1).argmax()))
    held = set(constrained.tolist())
    return {dim * a + i: float(u[a, i]) for a in nodes for i in range(dim) if dim * a + i not in held}


def body_checks(model: TractionModel, out: InternodesOutput, body: Body, summary_force: list[float],
                scale: float, label: str) -> tuple[list[Check], dict]:
    """Solve ``body`` alone in dolfinx with its contact traction; compare fields, reactions and force (and,
    for a body held by its contacts alone, the reactions of the dofs pinned at internodes' values).

    ``scale`` is the sum of the magnitudes of the body's contact forces, pair by pair: forces are
    compared relative to it, since a body between two others carries a net contact force of
    nothing (its two contacts balance) and the reactions of its rollers are round-off."""
    ours = out.body(body.name)
    where = f"{label} {body.name}"
    start = time.perf_counter()
    pinned = pins(model, body, ours.geometry[:, : model.dim], ours.displacement[:, : model.dim])
    ref = model.solve(body, pinned)
    pinned_reaction = ref.reactions.pop("pinned", None)
    force_ref = model.contact_force(body.name)
    seconds = time.perf_counter() - start
    u_ref = pad3(ref.displacement)
    stress_ref = ref.stress[cell_order(ours.cells, ref.cells, where)]
    force = np.asarray(summary_force[: model.dim], dtype=float)
    figures = {
        "displacement": relative_max(ours.displacement, u_ref),
        "stress": relative_max(ours.stress, stress_ref),
        "contact force": float(np.linalg.norm(force - force_ref) / scale),
    }
    reactions = reaction_check(ours.summary.get("reactions", {}), ref.reactions, where, scale)
    figures["reactions"] = reactions.figure
    checks = [
        Check("displacement", where, figures["displacement"], FIELD_TOLERANCE,
              f"max|u| = {abs(u_ref).max():.3e}, {len(u_ref)} nodes"),
        Check("stress", where, figures["stress"], FIELD_TOLERANCE,
              f"max|sigma| = {abs(stress_ref).max():.3e}, {len(stress_ref)} cells"),
        reactions,
        Check("contact force", where, figures["contact force"], FORCE_TOLERANCE,
              f"|F| = {np.linalg.norm(force_ref):.6e}, over the sum of its pairs' |F| {scale:.6e}"),
    ]
    if pinned_reaction is not None:
        # Held by its contacts alone: the pinned dofs carry no force in internodes' answer, so
        # their reaction in dolfinx is the balance of the body's loads, to the fields' precision.
        figures["pinned reaction"] = float(np.linalg.norm(pinned_reaction) / scale)
        checks.append(Check("pinned reaction", where, figures["pinned reaction"], FIELD_TOLERANCE,
                            f"{len(pinned)} dofs of a body held by its contacts alone pinned at internodes' "
                            f"displacement; |R| over the sum of its pairs' |F|"))
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
    case_file, data, tables = write_case(case, formulation, mesh, folder)
    output = folder / "internodes"
    shutil.rmtree(output, ignore_errors=True)  # never compare stale output
    start = time.perf_counter()
    solved = run_solve(binary, case_file, output)
    if solved.exit != 0:
        raise StepFailed(f"internodes solve {case_file} failed (exit {solved.exit}): {solved.tail(5)}")
    record = {"case": case.name, "mesh": case.description(), "formulation": formulation,
              "internodes_seconds": time.perf_counter() - start}

    summary = json.loads((output / "summary.json").read_text())
    pairs = summary["contacts"] if "contacts" in summary else [summary["contact"]]
    statuses = [p["status"] for p in pairs]
    record |= {"status": ", ".join(statuses), "iterations": len(pairs[0]["iterations"]),
               "active": [[p["active_primary"], p["active_secondary"]] for p in pairs],
               "force_imbalance": [p["force_imbalance"] for p in pairs]}
    checks = [Check("status", f"{label} {p['name']}" if len(pairs) > 1 else label,
                    0 if p["status"] == "converged" else 1, 0,
                    f"{p['status']}, {len(p['iterations'])} iterations, active "
                    f"{p['active_primary']} + {p['active_secondary']}") for p in pairs]
    forced = [r for p in pairs for r in (p["steps"][-1].get("forced") or [])]

    start = time.perf_counter()
    out = InternodesOutput(output)
    bodies = read_case(write_bodies(data, forced, folder)).bodies
    model = TractionModel(mesh, {b.name: out.body(b.name).geometry for b in bodies})
    tractions = contact_tractions(output, out)
    # Each body's contact surfaces and the total contact force on it, over the pairs it is in
    # (as solved: the primary may be "auto"'s, or the other body after a retry).
    sides: dict[str, tuple[list[str], np.ndarray, float]] = {}
    for table, pair in zip(tables, pairs):
        surfaces = contact_sides(table)
        for name, key in ((pair["primary"], "force_primary"), (pair["secondary"], "force_secondary")):
            groups, force, scale = sides.get(name, ([], np.zeros(len(pair[key])), 0.0))
            on_body = np.asarray(pair[key], dtype=float)
            sides[name] = (groups + [surfaces[name]], force + on_body, scale + float(np.linalg.norm(on_body)))
    record["bodies"] = {}
    for body in bodies:
        if body.name not in sides:
            continue
        groups, force, scale = sides[body.name]
        try:
            model.set_traction(body.name, groups, tractions[body.name])
            body_result, info = body_checks(model, out, body, list(force), scale, label)
            checks += body_result
            record["bodies"][body.name] = info | {"surfaces": groups}
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
        for formulation in case.formulations:
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
