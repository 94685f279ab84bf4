#!/usr/bin/python3
"""Several contact pairs in one case (``[[contact]]`` tables): three families with an exact or an
independent answer, gated.

Family 1, **a stack of three blocks** (``geo/stack_2d.geo``, ``geo/stack_3d.geo``): bottom, middle
and top blocks of width L = 1 and heights 0.6, 0.5, 0.4, Young's moduli 500, 3000, 1000 (nu = 0.3),
each meshed with its own size (2D 1/10, 1/13, 1/8; 3D 1/5, 1/7, 1/4, times 2^-level), so that
neither interface mesh matches; two pairs, top-middle and middle-bottom, the middle block held by
nothing but them along the vertical (a floating body). Rollers: every block's face x = 0 (and
y = 0 in 3D) held normally, the bottom block's base held vertically; the top block's top pushed
down by d = 0.01. The exact answer is a uniform uniaxial stress sigma (plane strain in 2D: the
out-of-plane strain is zero, the lateral faces free), with

    d = sigma * sum_i H_i c_i / E_i,   c_i = 1 - nu_i^2 (2D), 1 (3D),

the contact force of each pair P = sigma L^(dim - 1), and each block's displacement linear: the
vertical one -sigma c_i / E_i per unit height, the lateral one nu (1 + nu) sigma / E_i x (2D) or
nu sigma / E_i (x, y) (3D). P1 holds it exactly, and on flat faces the linearized gap is the gap:
the solver's answer must be the closed form to the precision of its linear solves. Rows, at every
load step: ``pair force`` (each pair's force on each of its two bodies against P, relative),
``pairs equal`` (the two pairs' forces on the middle block, relative to P), ``reactions`` (the
base's and the pushed face's reactions against P), ``middle top`` (the vertical displacement of
the middle block's top face against the closed form, relative to it) and ``field`` (every node's
displacement against the closed form, over d).

Family 2, **two half-discs pressed into one block** (``geo/two_discs_on_block_2d.geo``): two
lower half-discs of radius R = 1 (E = 1000, nu = 0.3), 3R apart centre to centre, on a block
8R x 2R whose base is clamped, each disc's flat top pushed down by d = 0.015 and held
laterally; two pairs that share the block. The mesh is mirror-symmetric about x = 0 (the geo
copies the right half's mesh onto the left; gmsh's copy places a few of the arcs' nodes up to 1e-7 R
off the mirror image, which ``symmetrize`` moves onto it, so that the mirror image is exact to
round-off: ``premise: mirror mesh``). The block is 1e3 times stiffer than the discs (E = 1e6): the
two indentations then interact only through the block, whose whole compliance is about 1e-3 of
the discs', so that the one-pair run of one disc on the same mesh (the other disc left out of
the case) is an independent answer for each pair's force, up to that interaction. Rows:
``mirror forces`` (the two pairs' forces, relative difference), ``one-pair force`` (each pair's
force against the one-pair run's, relative difference) and ``Hertz a`` (each pair's contact
half-width against Hertz's for its force, relative).

Family 3, **a disc floating between two plates, loaded by a force** (``geo/disc_between_plates_2d.geo``):
the half model x >= 0 of a disc of radius R = 1 between two plates 2R x R (all E = 1000,
nu = 0.3); the symmetry line x = 0 held normally on all three bodies (what frictionless contact
cannot hold on a round body: its lateral motion and turn), the lower plate's base clamped, the
upper plate's top a rigid loading plate (``[[body.force]]``, fy = -F, F = 2 per unit thickness of the
half model, and ux = 0). The disc is held vertically by its two contacts only, the upper plate by
its force and its contact. Then the same case with the upper plate's top moved by the displacement
the force run reports (``contacts[0].steps[-1].forced[0].displacement``) instead. Rows of the force
run: ``force control`` (the loading plate's reaction against F), ``statics`` (the forces that
statics alone fixes: the upper pair's force on the upper plate is F, the disc's two contact forces
cancel, the lower plate's base carries its contact force; the largest relative error), ``pair
force`` (each pair's force on each of its bodies against F: the interpolation transfer is not
conservative, so the two bodies of a pair carry forces that differ by the pair's
``force_imbalance``), ``Hertz a`` (each contact's half-width against Hertz's for a cylinder on a
half-space at the full model's force 2F); of the displacement run: ``displacement control``
(its force on the upper plate against F), ``approach`` (the floating disc's mean vertical
displacement against the force run's, relative) and ``same contact zone`` (the nodes in contact,
node for node: the discrete contact radius; every node's displacement against the force run's is
reported with it, not gated: the two runs reach their answers through different iterates, and
their fields differ at the rim of the zone by more than the loop's gap precision while forces and
approach agree to it; neither run pairs its interface again, the disc does not slide, so the
pairing is not the cause).

Every run also has, per pair, ``status`` (converged), ``solved`` and ``accuracy`` (the solver's
two reports, ``suite.report_rows``) and ``exit`` (0: the answer is trusted).

Tolerances (each fixed from what the exact or independent answer allows; a case is never given a
tolerance to pass):

* ``STACK_TOLERANCE`` = 1e-9: the exact answer is in the discrete space and the first solve's gap
  is exact, so only the linear solves' error remains: the coupled solve stops at a relative
  residual of 1e-12 (``coupled_krylov::TIGHT_RTOL``) and the body solves are direct (2D) or CG to
  1e-10 of the load (3D: ``[solver] rtol``, cholesky below 30,000 DOFs: these meshes are far
  below); 1e-9 leaves a factor 1e3 for the condition of the coupled system (the repository's own
  patch tests hold 1e-10 to 1e-12). A miss means the answer is not the exact discrete one: for
  example the loop stopped on its gap precision (1e-5 h) instead of the exact set-up.
* ``SYMMETRY_TOLERANCE`` = 1e-8: on a mirror-exact mesh the two pairs solve the same problem, up
  to the order of the floating-point operations (the two halves are numbered differently): the
  linear solves' error, 1e-12 relative residual, times the condition of the coupled system; 1e-8
  is the bound the repository's solver-agreement tests use (``tests/contact_solvers.rs``).
* ``one-pair force``: the other disc changes a pair's force only through the block, by about
  (dlnP / dln d) u_cross / d, where u_cross is the vertical displacement the one-pair run gives to
  the block's surface at the other disc's pole (the block's response there to one disc) and
  dlnP / dln d is 1 to 1.3 for the 2D Hertz law at these approaches; the tolerance is 2 |u_cross| / d
  from the one-pair run (not from the run it judges), plus 1e-8 for the solves.
* ``HERTZ_A_TOLERANCE`` = 0.03: the band of the Hertz suite for the 2D contact half-width
  (``hertz_suite.RELATIVE_2D_A``; its half-disc on a block at h_c = R/40 read 2.4%, at R/160
  0.28%): these contacts are meshed at R/80 (level 0) and R/160 (level 1). The fit is the Hertz
  suite's (least squares of p_i^2 against r_i^2 over the primary's loaded nodes, the mean
  pressure), with r measured from the known contact axis (the half model's axis is x = 0; the
  solver's own ``hertz_fit``, which fits the centre too, is listed for information).
* ``STATICS_TOLERANCE`` = 1e-9: a body's equilibrium in the answer (the loading plate's reaction
  F, the floating disc's two contact forces, the base reaction) holds to the linear solves'
  precision, as ``STACK_TOLERANCE``.
* ``IMBALANCE_TOLERANCE`` = 0.01: the two bodies of a pair carry forces that differ by the pair's
  ``force_imbalance`` (the interpolation transfer moves the multiplier's force onto the
  secondary through the interpolation, which is not conservative); the solver holds each pair's
  imbalance to ``imbalance_tolerance`` = 0.01 (its equilibrium check), so a pair's force may
  read up to that far from F on one of its bodies.
* ``control`` tolerance: the force run and the displacement run solve the same problem, and their
  loops stop when every active gap is within SETTLED * penetration_tolerance * h = 1e-5 h of the
  surface (``active_set::SETTLED``): their forces and the disc's position may then differ by
  1e-5 h / delta, h the contact spacing h_c, delta the approach; the tolerance is that bound.
  Their contact zones must be the same nodes (tolerance 0).

Usage:  /usr/bin/python3 validation/multi_body.py [--quick] [--binary PATH] [--cases NAME ...] [--out DIR]

Meshes, case files, outputs and logs go to validation/build/multi_body/.
"""

from __future__ import annotations

import json
import math
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import h5py
import numpy as np

VALIDATION = Path(__file__).resolve().parent
REPO = VALIDATION.parent

import hertz_theory  # noqa: E402
from compare import Check  # noqa: E402
from contact_reference import ellipse_fit  # noqa: E402
from suite import (checks_table, run_cases, standalone, Figure, MeshFailed, SuiteResult, json_safe, mesh_geo, report_rows, run_solve,  # noqa: E402
                   toml_text)

BUILD = VALIDATION / "build" / "multi_body"

# Tolerances (module doc).
STACK_TOLERANCE = 1e-9
SYMMETRY_TOLERANCE = 1e-8
HERTZ_A_TOLERANCE = 0.03
STATICS_TOLERANCE = 1e-9
IMBALANCE_TOLERANCE = 0.01
SETTLED_GAP_OVER_H = 0.01 * 1e-3  # active_set::SETTLED x the default penetration_tolerance
SOLVE_PRECISION = 1e-8  # added to tolerances that are physical bounds: the linear solves' share
MIRROR_PREMISE = 1e-12  # the mirrored mesh's largest node offset from the exact image, over R

# Family 1: the stack (module doc).
STACK = {"L": 1.0, "H": {"bottom": 0.6, "middle": 0.5, "top": 0.4},
         "E": {"bottom": 500.0, "middle": 3000.0, "top": 1000.0}, "nu": 0.3, "d": 0.01}
# Family 2: two half-discs on a stiff block.
DISCS = {"R": 1.0, "s": 3.0, "E_disc": 1000.0, "E_block": 1e6, "nu": 0.3, "d": 0.015}
# Family 3: a disc between two plates, the upper one loaded by a force.
PLATES = {"R": 1.0, "E": 1000.0, "nu": 0.3, "F": 2.0}


@dataclass(frozen=True)
class MultiCase:
    name: str
    kind: str  # "stack" | "two-discs" | "disc-plates"
    dim: int
    level: int
    load_steps: tuple = ()  # top-level load_steps (empty: the default, one step at 1)
    quick: bool = False
    why: str = ""
    timeout: float = 900.0

    @property
    def script(self) -> str:
        return {"stack": f"stack_{self.dim}d", "two-discs": "two_discs_on_block_2d",
                "disc-plates": "disc_between_plates_2d"}[self.kind]

    @property
    def h_c(self) -> float:
        """The contact spacing of the curved cases (the geo default R/80 at level 0)."""
        return 1.0 / 80 / 2**self.level


CASES = (
    MultiCase("stack-2d", "stack", 2, 0, (0.5, 1.0), quick=True,
              why="three blocks, two non-matching flat interfaces, the middle block floating; load steps 0.5, 1"),
    MultiCase("stack-2d-l1", "stack", 2, 1,
              why="the same, every size halved, one step: the exact answer from one solve"),
    MultiCase("stack-3d", "stack", 3, 0, (0.5, 1.0), quick=True,
              why="3D stack on rollers (x = 0 and y = 0 faces), load steps 0.5, 1"),
    MultiCase("stack-3d-l1", "stack", 3, 1, why="3D stack, every size halved, one step"),
    MultiCase("two-discs", "two-discs", 2, 0, quick=True,
              why="two half-discs side by side on one stiff block (E ratio 1e3), mirror-symmetric mesh, h_c = R/80"),
    MultiCase("two-discs-l1", "two-discs", 2, 1, why="the same at h_c = R/160"),
    MultiCase("disc-plates", "disc-plates", 2, 0, quick=True,
              why="half model of a disc between two plates, the upper plate loaded by a force; then by the "
                  "displacement the force gave; h_c = R/80"),
    MultiCase("disc-plates-l1", "disc-plates", 2, 1, why="the same at h_c = R/160"),
)


class RunFailed(RuntimeError):
    """Meshing, solving or reading failed; the message says which and why."""


# ---------------------------------------------------------------------------
# Meshes
# ---------------------------------------------------------------------------


def mesh(case: MultiCase) -> tuple[Path, dict]:
    """The case's mesh (cached by ``suite.mesh_geo``), and for the two discs the mirror premise."""
    path = BUILD / "meshes" / f"{case.script}_l{case.level}.msh"
    try:
        msh = mesh_geo(case.script, case.dim, {"level": case.level}, path)
    except MeshFailed as error:
        raise RunFailed(str(error)) from error
    if case.kind != "two-discs":
        return msh, {}
    return symmetrize(msh, path.with_name(f"{case.script}_l{case.level}_mirror.msh"))


def _body_nodes(model, name: str, dim: int) -> np.ndarray:
    for d, t in model.getPhysicalGroups(dim):
        if model.getPhysicalName(d, t) == name:
            tags = [model.mesh.getElements(dim, e)[2][0] for e in model.getEntitiesForPhysicalGroup(d, t)]
            return np.unique(np.concatenate(tags).astype(int))
    raise RunFailed(f"no physical group '{name}' of dimension {dim}")


def symmetrize(msh: Path, out: Path) -> tuple[Path, dict]:
    """Move every node of the left half (x < 0) onto the exact mirror image of its partner on the
    right (block onto block, left disc onto right disc), and measure the largest move (gmsh's
    periodic copy of a curved line) and the largest offset left afterwards (the premise row)."""
    import gmsh
    from scipy.spatial import cKDTree

    gmsh.initialize(["gmsh", "-v", "0"])
    try:
        gmsh.open(str(msh))
        tags, coords, _ = gmsh.model.mesh.getNodes()
        x = np.zeros((int(tags.max()) + 1, 3))
        x[tags.astype(int)] = coords.reshape(-1, 3)
        moved, unmatched = 0.0, 0
        flip = np.array([-1.0, 1.0, 1.0])
        for left_body, right_body in (("disc_left", "disc_right"), ("block", "block")):
            left = _body_nodes(gmsh.model, left_body, 2)
            right = _body_nodes(gmsh.model, right_body, 2)
            left = left[x[left, 0] < -1e-12]
            right = right[x[right, 0] > 1e-12]
            distance, k = cKDTree(x[right] * flip).query(x[left])
            unmatched += int((distance > 1e-6).sum()) + abs(len(left) - len(right))
            moved = max(moved, float(distance.max()))
            for tag, partner in zip(left, right[k]):
                gmsh.model.mesh.setNode(int(tag), list(x[partner] * flip), [])
        tags, coords, _ = gmsh.model.mesh.getNodes()
        y = np.zeros((int(tags.max()) + 1, 3))
        y[tags.astype(int)] = coords.reshape(-1, 3)
        offset = 0.0
        for left_body, right_body in (("disc_left", "disc_right"), ("block", "block")):
            left = _body_nodes(gmsh.model, left_body, 2)
            right = _body_nodes(gmsh.model, right_body, 2)
            left, right = left[y[left, 0] < -1e-12], right[y[right, 0] > 1e-12]
            offset = max(offset, float(cKDTree(y[right] * flip).query(y[left])[0].max()))
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.write(str(out))
    finally:
        gmsh.finalize()
    return out, {"mirror_moved": moved, "mirror_offset": offset, "mirror_unmatched": unmatched}


# ---------------------------------------------------------------------------
# Case files, runs, outputs
# ---------------------------------------------------------------------------


def pair(name: str, bodies: tuple[str, str], surfaces: tuple[str, str]) -> dict:
    return {"name": name, "bodies": list(bodies), "surfaces": list(surfaces), "primary": "auto"}


def body(name: str, e: float, nu: float, dirichlet: list[tuple[str, dict]], force: list[tuple[str, dict]] = ()) -> dict:
    table = {"name": name, "youngs_modulus": e, "poisson_ratio": nu,
             "dirichlet": [{"group": g, **v} for g, v in dirichlet]}
    if force:
        table["force"] = [{"group": g, **v} for g, v in force]
    return table


def case_text(msh: Path, output: Path, pairs: list[dict], bodies: list[dict], load_steps: tuple,
              comment: str) -> str:
    """A case file with ``[[contact]]`` tables (several pairs) or one ``[contact]`` table."""
    case: dict = {"mesh": str(msh), "output": str(output)}
    if load_steps:
        case["load_steps"] = list(load_steps)
    case["contact"] = pairs if len(pairs) > 1 else pairs[0]
    case["body"] = bodies
    return f"# {comment} (written by validation/multi_body.py)\n" + toml_text(case)


def solve(binary: Path, case: MultiCase, label: str, text: str) -> dict:
    """Write the case, run internodes, read its answer; no answer at all is RunFailed."""
    folder = BUILD / f"{case.name}-{label}"
    folder.mkdir(parents=True, exist_ok=True)
    output = folder / "internodes"
    toml = folder / "case.toml"
    toml.write_text(text)
    run = run_solve(binary, toml, output, case.timeout, folder / "log.txt")
    if not (output / "summary.json").is_file() or not (output / "solution.h5").is_file():
        raise RunFailed(f"{label}: internodes wrote no solution (exit {run.exit}, {run.seconds:.1f} s): {run.tail()}")
    summary = json.loads((output / "summary.json").read_text())
    pairs = summary.get("contacts")
    if pairs is None and isinstance(summary.get("contact"), dict):
        pairs = [summary["contact"]]
    if not isinstance(pairs, list) or not pairs:
        raise RunFailed(f"{label}: summary.json has neither 'contacts' nor 'contact'")
    with h5py.File(output / "solution.h5", "r") as h5:
        fields = {n.split("/")[1]: h5[n][()] for n in ("mesh/geometry", "mesh/node_body", "fields/displacement",
                                                       "fields/contact_mean_pressure", "fields/contact_active")}
    return {"summary": summary, "pairs": pairs, "exit": run.exit, "seconds": run.seconds, "label": label,
            "body_names": [b["name"] for b in summary["bodies"]], **fields}


def pair_force(contact: dict, body_name: str, dim: int, step: dict | None = None) -> float:
    """The vertical contact force on ``body_name`` of a pair (a step's when given)."""
    source = step if step is not None else contact
    if contact.get("primary") == body_name:
        return float(source["force_primary"][dim - 1])
    if contact.get("secondary") == body_name:
        return float(source["force_secondary"][dim - 1])
    raise RunFailed(f"pair {contact.get('name')}: '{body_name}' is neither its primary nor its secondary")


def reaction(out: dict, body_name: str, group: str, dim: int) -> float:
    for b in out["summary"]["bodies"]:
        if b["name"] == body_name:
            return float(b["reactions"][group][dim - 1])
    raise RunFailed(f"no body '{body_name}' in summary.json")


def run_rows(case: MultiCase, out: dict, expected_pairs: list[str]) -> list[Check]:
    """Per run: exit 0, and per pair (in case-file order): its name, converged, both reports."""
    label = f"{case.name} {out['label']}"
    names = [c.get("name") for c in out["pairs"]]
    rows = [Check("exit", label, 0.0 if out["exit"] == 0 else 1.0, 0.0,
                  f"exit {out['exit']}, {out['seconds']:.1f} s; pairs {names}"),
            Check("pairs", label, 0.0 if names == expected_pairs else 1.0, 0.0,
                  f"summary pairs {names}, the case file's {expected_pairs} (in order)")]
    for contact in out["pairs"]:
        where = f"{label} {contact.get('name')}"
        status = contact.get("status")
        rows.append(Check("status", where, 0.0 if status == "converged" else 1.0, 0.0,
                          f"{status}, primary {contact.get('primary')}, transfer "
                          f"{(contact.get('transfer') or {}).get('transfer')}, force_imbalance "
                          f"{contact.get('force_imbalance', math.nan):.2e}, {contact.get('active_primary')} active"))
        rows += report_rows(where, contact)
    return rows


# ---------------------------------------------------------------------------
# Family 1: the stack
# ---------------------------------------------------------------------------


def stack_exact(dim: int) -> dict:
    s = STACK
    c = {b: (1 - s["nu"] ** 2 if dim == 2 else 1.0) / s["E"][b] for b in s["E"]}
    sigma = s["d"] / sum(s["H"][b] * c[b] for b in c)
    return {"sigma": sigma, "force": sigma * s["L"] ** (dim - 1), "compliance": c}


def stack_field(x: np.ndarray, block: str, dim: int, factor: float) -> np.ndarray:
    """The exact displacement of ``block`` at the nodes ``x`` under the load factor."""
    s, ex = STACK, stack_exact(dim)
    sigma, c = ex["sigma"] * factor, ex["compliance"]
    order = ["bottom", "middle", "top"]
    y0 = sum(s["H"][b] for b in order[: order.index(block)])
    u0 = -sum(sigma * c[b] * s["H"][b] for b in order[: order.index(block)])
    u = np.zeros((len(x), 3))
    v = dim - 1
    u[:, v] = u0 - sigma * c[block] * (x[:, v] - y0)
    lateral = s["nu"] * (1 + s["nu"]) if dim == 2 else s["nu"]
    for k in range(dim - 1):
        u[:, k] = lateral * sigma / s["E"][block] * x[:, k]
    return u


def stack_case(case: MultiCase, msh: Path, output: Path) -> str:
    s, dim = STACK, case.dim
    v = "uy" if dim == 2 else "uz"
    rollers = {b: [(f"{b}_left", {"ux": 0.0})] if dim == 2 else [(f"{b}_x0", {"ux": 0.0}), (f"{b}_y0", {"uy": 0.0})]
               for b in s["E"]}
    bodies = [body("top", s["E"]["top"], s["nu"], [("top_load", {v: -s["d"]})] + rollers["top"]),
              body("middle", s["E"]["middle"], s["nu"], rollers["middle"]),
              body("bottom", s["E"]["bottom"], s["nu"], [("bottom_base", {v: 0.0})] + rollers["bottom"])]
    pairs = [pair("top-middle", ("top", "middle"), ("top_bottom", "middle_top")),
             pair("middle-bottom", ("middle", "bottom"), ("middle_bottom", "bottom_top"))]
    return case_text(msh, output, pairs, bodies, case.load_steps, f"{case.name}: {case.why}")


def stack_checks(binary: Path, case: MultiCase, msh: Path) -> tuple[list[Check], dict]:
    out = solve(binary, case, "stack", stack_case(case, msh, BUILD / f"{case.name}-stack" / "internodes"))
    dim, s = case.dim, STACK
    ex = stack_exact(dim)
    checks = run_rows(case, out, ["top-middle", "middle-bottom"])
    top_middle, middle_bottom = out["pairs"]
    steps = list(zip(top_middle.get("steps", []), middle_bottom.get("steps", [])))
    expected_steps = list(case.load_steps) or [1.0]
    if len(steps) != len(expected_steps):
        checks.append(Check("steps", case.name, math.nan, 0.0,
                            f"{len(steps)} steps reported, {len(expected_steps)} asked"))
    record = {"exit": out["exit"], "seconds": out["seconds"], "P_exact": ex["force"], "steps": []}
    for k, (a, b) in enumerate(steps):
        factor = float(a.get("load_factor", math.nan))
        p = ex["force"] * factor
        forces = {"top-middle": {"top": pair_force(top_middle, "top", dim, a),
                                 "middle": pair_force(top_middle, "middle", dim, a)},
                  "middle-bottom": {"middle": pair_force(middle_bottom, "middle", dim, b),
                                    "bottom": pair_force(middle_bottom, "bottom", dim, b)}}
        where = f"{case.name} step {k + 1} (factor {factor:g})"
        for name, by_body in forces.items():
            errors = {n: abs(abs(f) / p - 1) for n, f in by_body.items()}
            checks.append(Check("pair force", f"{where} {name}", max(errors.values()), STACK_TOLERANCE,
                                ", ".join(f"on {n} {f:.12g}" for n, f in by_body.items()) + f"; exact {p:.12g}"))
        m1, m2 = forces["top-middle"]["middle"], forces["middle-bottom"]["middle"]
        checks.append(Check("pairs equal", where, abs(abs(m1) - abs(m2)) / p, STACK_TOLERANCE,
                            f"the two pairs' forces on the middle block {m1:.12g}, {m2:.12g}"))
        record["steps"].append({"factor": factor, "forces": forces})
    # The final state: reactions, the middle block's top, every node's displacement.
    p = ex["force"] * expected_steps[-1]
    base, pushed = reaction(out, "bottom", "bottom_base", dim), reaction(out, "top", "top_load", dim)
    checks.append(Check("reactions", case.name, max(abs(abs(base) / p - 1), abs(abs(pushed) / p - 1)),
                        STACK_TOLERANCE, f"base {base:.12g}, pushed face {pushed:.12g}; exact {p:.12g}"))
    x, u, nb = out["geometry"], out["displacement"], out["node_body"]
    v = dim - 1
    worst, where = 0.0, ""
    for block in ("bottom", "middle", "top"):
        on = nb == out["body_names"].index(block)
        error = np.abs(u[on, :dim] - stack_field(x[on], block, dim, expected_steps[-1])[:, :dim]).max(axis=1)
        if error.max() > worst:
            worst, where = float(error.max()), f"{block} node at {np.round(x[on][error.argmax(), :dim], 4).tolist()}"
        if block == "middle":
            top = np.abs(x[on, v] - (s["H"]["bottom"] + s["H"]["middle"])) < 1e-9
            exact = stack_field(x[on][top], "middle", dim, expected_steps[-1])[:, v]
            rel = np.abs(u[on][top, v] - exact).max() / abs(exact[0])
            checks.append(Check("middle top", case.name, rel, STACK_TOLERANCE,
                                f"{int(top.sum())} nodes of the middle block's top face: u_v from "
                                f"{u[on][top, v].min():.12g} to {u[on][top, v].max():.12g}, exact {exact[0]:.12g}"))
            record["middle_top"] = {"min": float(u[on][top, v].min()), "max": float(u[on][top, v].max()),
                                    "exact": float(exact[0])}
    d = s["d"] * expected_steps[-1]
    checks.append(Check("field", case.name, worst / d, STACK_TOLERANCE,
                        f"largest |u - u_exact| {worst:.3e} ({where}), over d = {d:g}"))
    record["field_error_over_d"] = worst / d
    return checks, record


# ---------------------------------------------------------------------------
# Hertz half-width of one contact, r from a known axis
# ---------------------------------------------------------------------------


def contact_half_width(out: dict, contact: dict, centre: tuple[float, float], radius: float, dim: int = 2) -> dict:
    """Ellipse fit of the primary's mean pressure over its loaded nodes within ``radius`` of the
    contact point ``centre`` (r the lateral distance from it), as ``sweep.hertz_fit``."""
    primary = contact.get("primary")
    x, p = out["geometry"], out["contact_mean_pressure"]
    on = (out["node_body"] == out["body_names"].index(primary)) & (out["contact_active"] > 0.5)
    on &= np.hypot(x[:, 0] - centre[0], x[:, 1] - centre[1]) < radius
    if not on.any():
        return {"a": math.nan, "nodes": 0}
    on &= p > 1e-9 * p[on].max()
    r = np.abs(x[on, 0] - centre[0])
    fit = ellipse_fit(r, p[on])
    return {"a": fit["a"] if fit else math.nan, "p0": fit["p0"] if fit else math.nan, "nodes": int(on.sum()),
            "r": r.tolist(), "p": p[on].tolist(), "primary": primary}


def hertz_check(case: MultiCase, where: str, fit: dict, force: float, radius: float, e_star: float,
                contact: dict) -> tuple[Check, dict]:
    theory = hertz_theory.contact(force, radius, e_star, 2)
    figure = abs(fit["a"] / theory["a"] - 1) if math.isfinite(fit["a"]) else math.nan
    solver = (contact.get("hertz_fit") or {}).get("a")
    note = (f"a = {fit['a']:.5g} (fit on {fit['nodes']} loaded nodes of {fit.get('primary')}, r from the axis), "
            f"a_H = {theory['a']:.5g} for P = {force:.6g}, E* = {e_star:.6g}; the solver's hertz_fit a = "
            f"{solver if solver is None else f'{solver:.5g}'}")
    return Check("Hertz a", where, figure, HERTZ_A_TOLERANCE, note), {"a": fit["a"], "a_H": theory["a"],
                                                                       "p0": fit.get("p0"), "p0_H": theory["p0"]}


# ---------------------------------------------------------------------------
# Family 2: two half-discs on one block
# ---------------------------------------------------------------------------


def discs_case(case: MultiCase, msh: Path, output: Path, sides: tuple[str, ...]) -> str:
    c = DISCS
    bodies = [body(f"disc_{side}", c["E_disc"], c["nu"], [(f"disc_{side}_top", {"ux": 0.0, "uy": -c["d"]})])
              for side in sides]
    bodies.append(body("block", c["E_block"], c["nu"], [("block_base", {"ux": 0.0, "uy": 0.0})]))
    pairs = [pair(f"disc_{side}-block", (f"disc_{side}", "block"), (f"disc_{side}_contact", f"block_contact_{side}"))
             for side in sides]
    return case_text(msh, output, pairs, bodies, case.load_steps, f"{case.name} ({'+'.join(sides)}): {case.why}")


def block_surface_uy(out: dict, x0: float) -> float:
    x = out["geometry"]
    on = (out["node_body"] == out["body_names"].index("block")) & (np.abs(x[:, 1]) < 1e-12)
    k = np.where(on)[0][np.argmin(np.abs(x[on, 0] - x0))]
    if abs(x[k, 0] - x0) > 1e-9:
        raise RunFailed(f"no block node at ({x0}, 0)")
    return float(out["displacement"][k, 1])


def discs_checks(binary: Path, case: MultiCase, msh: Path, premise: dict) -> tuple[list[Check], dict]:
    c = DISCS
    xc = c["s"] / 2
    checks = [Check("premise: mirror mesh", case.name,
                    premise["mirror_offset"] / c["R"] if premise["mirror_unmatched"] == 0 else math.nan,
                    MIRROR_PREMISE,
                    f"largest offset of a left-half node from the mirror image of its partner {premise['mirror_offset']:.2e} "
                    f"after moving them (gmsh's copy: up to {premise['mirror_moved']:.2e}); "
                    f"{premise['mirror_unmatched']} nodes without a partner")]
    two = solve(binary, case, "two", discs_case(case, msh, BUILD / f"{case.name}-two" / "internodes",
                                                ("left", "right")))
    one = solve(binary, case, "one", discs_case(case, msh, BUILD / f"{case.name}-one" / "internodes", ("right",)))
    checks += run_rows(case, two, ["disc_left-block", "disc_right-block"])
    checks += run_rows(case, one, ["disc_right-block"])
    left, right = two["pairs"]
    p_left, p_right = abs(pair_force(left, "disc_left", 2)), abs(pair_force(right, "disc_right", 2))
    p_one = abs(pair_force(one["pairs"][0], "disc_right", 2))
    checks.append(Check("mirror forces", case.name, abs(p_left - p_right) / p_right, SYMMETRY_TOLERANCE,
                        f"force on the left disc {p_left:.12g}, on the right disc {p_right:.12g}"))
    # The one-pair run's block under the other disc's pole: the interaction through the block.
    u_cross, u_own = block_surface_uy(one, -xc), block_surface_uy(one, xc)
    tolerance = 2 * abs(u_cross) / c["d"] + SOLVE_PRECISION
    for name, p in (("disc_left-block", p_left), ("disc_right-block", p_right)):
        checks.append(Check("one-pair force", f"{case.name} {name}", abs(p / p_one - 1), tolerance,
                            f"two pairs: {p:.10g}; the right disc alone: {p_one:.10g}; predicted interaction "
                            f"u_cross / d = {u_cross / c['d']:.3e} (the block's surface under the other pole moves "
                            f"{u_cross:.3e} in the one-pair run, under its own disc {u_own:.3e})"))
    e_star = hertz_theory.contact_modulus([(c["E_disc"], c["nu"]), (c["E_block"], c["nu"])])
    record = {"exit": [two["exit"], one["exit"]], "seconds": two["seconds"] + one["seconds"],
              "forces": {"left": p_left, "right": p_right, "one": p_one}, "u_cross": u_cross, "u_own": u_own,
              "hertz": {}, "profiles": {}}
    for contact, sign, p in ((left, -1, p_left), (right, 1, p_right)):
        fit = contact_half_width(two, contact, (sign * xc, 0.0), 0.5 * c["R"])
        check, data = hertz_check(case, f"{case.name} {contact.get('name')}", fit, p, c["R"], e_star, contact)
        checks.append(check)
        record["hertz"][contact.get("name")] = data
        record["profiles"][contact.get("name")] = {"r": fit.get("r", []), "p": fit.get("p", []), "P": p,
                                                   "e_star": e_star, "R": c["R"]}
    return checks, record


# ---------------------------------------------------------------------------
# Family 3: a disc between two plates
# ---------------------------------------------------------------------------


def plates_case(case: MultiCase, msh: Path, output: Path, imposed: float | None) -> str:
    c = PLATES
    if imposed is None:
        top = body("top", c["E"], c["nu"], [("top_load", {"ux": 0.0}), ("top_axis", {"ux": 0.0})],
                   [("top_load", {"fy": -c["F"]})])
    else:
        top = body("top", c["E"], c["nu"], [("top_load", {"ux": 0.0, "uy": imposed}), ("top_axis", {"ux": 0.0})])
    bodies = [top, body("disc", c["E"], c["nu"], [("disc_axis", {"ux": 0.0})]),
              body("bottom", c["E"], c["nu"], [("bottom_base", {"ux": 0.0, "uy": 0.0}), ("bottom_axis", {"ux": 0.0})])]
    pairs = [pair("top-disc", ("top", "disc"), ("top_contact", "disc_upper")),
             pair("disc-bottom", ("disc", "bottom"), ("disc_lower", "bottom_contact"))]
    how = "force" if imposed is None else f"displacement {imposed:.12g}"
    return case_text(msh, output, pairs, bodies, case.load_steps, f"{case.name} ({how}): {case.why}")


def plates_checks(binary: Path, case: MultiCase, msh: Path) -> tuple[list[Check], dict]:
    c = PLATES
    F, R = c["F"], c["R"]
    force = solve(binary, case, "force", plates_case(case, msh, BUILD / f"{case.name}-force" / "internodes", None))
    checks = run_rows(case, force, ["top-disc", "disc-bottom"])
    top_disc, disc_bottom = force["pairs"]
    forced = (top_disc.get("steps") or [{}])[-1].get("forced") or []
    if not forced:
        raise RunFailed("the force run reports no forced displacement (contacts[0].steps[-1].forced)")
    delta = float(forced[0]["displacement"])
    on_top = pair_force(top_disc, "top", 2)
    on_disc_up, on_disc_low = pair_force(top_disc, "disc", 2), pair_force(disc_bottom, "disc", 2)
    on_bottom = pair_force(disc_bottom, "bottom", 2)
    load = reaction(force, "top", "top_load", 2)
    base = reaction(force, "bottom", "bottom_base", 2)
    checks.append(Check("force control", case.name, abs(abs(load) / F - 1), STATICS_TOLERANCE,
                        f"the loading plate's reaction {load:.12g}, F = {F:g}; its displacement {delta:.10g}"))
    statics = {"upper pair on the upper plate = F": abs(abs(on_top) / F - 1),
               "disc: the two contact forces cancel": abs(on_disc_up + on_disc_low) / F,
               "lower plate: base reaction = its contact force": abs(abs(base) - abs(on_bottom)) / F}
    checks.append(Check("statics", case.name, max(statics.values()), STATICS_TOLERANCE,
                        "; ".join(f"{k}: {v:.2e}" for k, v in statics.items())
                        + f" (forces: on the upper plate {on_top:.12g}, on the disc {on_disc_up:.12g} and "
                          f"{on_disc_low:.12g}, on the lower plate {on_bottom:.12g}, base {base:.12g})"))
    for contact, bodies in ((top_disc, ("top", "disc")), (disc_bottom, ("disc", "bottom"))):
        values = {b: pair_force(contact, b, 2) for b in bodies}
        checks.append(Check("pair force", f"{case.name} {contact.get('name')}",
                            max(abs(abs(v) / F - 1) for v in values.values()), IMBALANCE_TOLERANCE,
                            ", ".join(f"on {b} {v:.10g}" for b, v in values.items())
                            + f"; F = {F:g}; force_imbalance {contact.get('force_imbalance', math.nan):.2e}"))
    # Hertz: the full model's force 2F on a cylinder of radius R between equal bodies.
    e_star = hertz_theory.contact_modulus([(c["E"], c["nu"])] * 2)
    record = {"exit": [force["exit"]], "seconds": force["seconds"], "delta": delta,
              "forces": {"on_top": on_top, "on_disc_upper": on_disc_up, "on_disc_lower": on_disc_low,
                         "on_bottom": on_bottom, "load": load, "base": base}, "hertz": {}, "profiles": {}}
    for contact, centre in ((top_disc, (0.0, 2 * R)), (disc_bottom, (0.0, 0.0))):
        p_full = 2 * abs(pair_force(contact, "disc", 2))
        fit = contact_half_width(force, contact, centre, 0.5 * R)
        check, data = hertz_check(case, f"{case.name} {contact.get('name')}", fit, p_full, R, e_star, contact)
        check.note += " (half model: P is twice the pair's force)"
        checks.append(check)
        record["hertz"][contact.get("name")] = data
        record["profiles"][contact.get("name")] = {"r": fit.get("r", []), "p": fit.get("p", []), "P": p_full,
                                                   "e_star": e_star, "R": R}
    # The same case pressed by the displacement the force gave.
    shown = solve(binary, case, "displacement",
                  plates_case(case, msh, BUILD / f"{case.name}-displacement" / "internodes", delta))
    checks += run_rows(case, shown, ["top-disc", "disc-bottom"])
    record["exit"].append(shown["exit"])
    record["seconds"] += shown["seconds"]
    on_top_d = pair_force(shown["pairs"][0], "top", 2)
    load_d = reaction(shown, "top", "top_load", 2)
    h = case.h_c
    force_tolerance = SETTLED_GAP_OVER_H * h / abs(delta) + SOLVE_PRECISION
    checks.append(Check("displacement control", case.name,
                        max(abs(abs(on_top_d) / F - 1), abs(abs(load_d) / F - 1)), force_tolerance,
                        f"upper plate moved {delta:.10g}: its contact force {on_top_d:.12g}, its top's reaction "
                        f"{load_d:.12g}; F = {F:g}; tolerance 1e-5 h_c / |delta| (h_c = {h:g})"))
    # The approach: the floating disc's rigid position, its mean vertical displacement.
    disc = force["node_body"] == force["body_names"].index("disc")
    position = force["displacement"][disc, 1].mean(), shown["displacement"][disc, 1].mean()
    checks.append(Check("approach", case.name, abs(position[1] / position[0] - 1), force_tolerance,
                        f"the disc's mean vertical displacement {position[0]:.12g} (force run), {position[1]:.12g} "
                        f"(displacement run); tolerance 1e-5 h_c / |delta| (a rigid shift of the disc by the "
                        f"settling precision of a gap)"))
    if force["geometry"].shape != shown["geometry"].shape or np.abs(force["geometry"] - shown["geometry"]).max() > 0:
        raise RunFailed("the force and displacement runs have different meshes")
    # The contact zone: the same nodes in contact (primary: active; secondary: compressed and
    # touching), node for node. The field itself is reported, not gated: the two runs reach
    # their answers through different iterates, and their nodal fields differ by more than the
    # gap-settling precision at the rim of the zone (measured: 1.4e-5 of the approach at level
    # 1), while their forces and approach agree to it. Neither run pairs its interface again
    # (the disc does not slide: the answers are the same bit for bit whether the pairing
    # follows the slide on a grid or from 0.05 spacings), so the pairing is not the cause.
    zones = force["contact_active"] != 0, shown["contact_active"] != 0
    differing = int(np.count_nonzero(zones[0] != zones[1]))
    difference = np.abs(force["displacement"] - shown["displacement"]).max(axis=1)
    k = int(difference.argmax())
    checks.append(Check("same contact zone", case.name, float(differing), 0.0,
                        f"nodes in contact: {int(zones[0].sum())} (force run), {int(zones[1].sum())} "
                        f"(displacement run), {differing} differing; for information, the largest "
                        f"|u_force - u_displacement| {difference[k]:.3e} at "
                        f"{np.round(force['geometry'][k, :2], 4).tolist()} (body "
                        f"{force['body_names'][force['node_body'][k]]}), {difference[k] / abs(delta):.2e} of "
                        f"|delta| = {abs(delta):.6g}"))
    record["displacement_run"] = {"on_top": on_top_d, "load": load_d, "max_difference": float(difference[k])}
    return checks, record


# ---------------------------------------------------------------------------
# The suite
# ---------------------------------------------------------------------------


def run_case(binary: Path, case: MultiCase) -> tuple[list[Check], dict]:
    """Mesh, solve(s), checks. Anything that fails is a failed row, never a skip."""
    record: dict = {"parameters": asdict(case)}
    try:
        msh, premise = mesh(case)
        record["mesh"] = str(msh)
        record |= premise
        if case.kind == "stack":
            checks, data = stack_checks(binary, case, msh)
        elif case.kind == "two-discs":
            checks, data = discs_checks(binary, case, msh, premise)
        else:
            checks, data = plates_checks(binary, case, msh)
        record |= data
    except (RunFailed, OSError, KeyError, ValueError, TypeError, IndexError, json.JSONDecodeError) as error:
        checks = [Check("run", case.name, math.nan, 0.0, f"{type(error).__name__}: {error}")]
        record["error"] = f"{type(error).__name__}: {error}"
    return checks, record


def plot_profiles(records: dict, path: Path) -> bool:
    """Each curved contact's pressure against Hertz's ellipse for its force."""
    rows = [(name, pair_name, profile) for name, r in records.items()
            for pair_name, profile in (r.get("profiles") or {}).items() if profile.get("r")]
    if not rows:
        return False
    import contact_reference
    plt = contact_reference._pyplot()
    columns = min(4, len(rows))
    lines = -(-len(rows) // columns)
    fig, axes = plt.subplots(lines, columns, figsize=(3.2 * columns, 3.0 * lines), squeeze=False)
    for ax in axes.flat[len(rows):]:
        ax.set_visible(False)
    for ax, (name, pair_name, prof) in zip(axes.flat, rows):
        theory = hertz_theory.contact(prof["P"], prof["R"], prof["e_star"], 2)
        r = np.linspace(0, theory["a"], 100)
        ax.plot(r / theory["a"], theory["p0"] * np.sqrt(1 - (r / theory["a"]) ** 2) / theory["p0"], "k-", lw=1,
                label="Hertz")
        ax.plot(np.array(prof["r"]) / theory["a"], np.array(prof["p"]) / theory["p0"], "o", ms=3, mfc="none",
                label="internodes")
        ax.set_title(f"{name}\n{pair_name}", fontsize=8)
        ax.set_xlabel("r / a_H", fontsize=8)
        ax.grid(alpha=0.3)
    for row in axes:
        row[0].set_ylabel("p / p0_H", fontsize=8)
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def run_suite(binary: Path, quick: bool, out_dir: Path, names: list[str] | None = None) -> SuiteResult:
    start = time.perf_counter()
    out_dir.mkdir(parents=True, exist_ok=True)
    cases = [c for c in CASES if (c.quick or not quick) and (not names or c.name in names)]
    checks, records = run_cases(cases, lambda case: run_case(binary, case), lambda case: case.why)
    figures = []
    png = out_dir / "multi_body_pressure.png"
    try:
        if plot_profiles(records, png):
            figures.append(Figure("Several pairs: each curved contact's pressure (the primary's mean nodal pressure, "
                                  "r from the contact axis) against Hertz's ellipse for its force", png))
    except Exception as error:  # a figure is information; its failure is a note, not a check
        print(f"    (no figure: {type(error).__name__}: {error})")
    seconds = time.perf_counter() - start
    text = report_text(cases, checks, records, quick, seconds)
    for r in records.values():
        r.pop("profiles", None)
    return SuiteResult("Several contact pairs in one case: a three-block stack, two discs on one block, a disc "
                       "between two plates (gate)", checks, figures, text,
                       {"quick": quick, "seconds": seconds, "cases": json_safe(records)})


DECISIONS = """\
**Decisions** (module doc of `validation/multi_body.py`; tolerances fixed from the exact or
independent answer, before any run was judged):

* *Stack*: the exact uniaxial stress is in the P1 space and the gap of flat faces is linear, so
  the answer must be the closed form to the linear solves' precision (1e-9; the coupled solve
  stops at a residual of 1e-12).
* *Two discs*: the mesh is mirror-exact (checked), so the two pairs' forces may differ by the
  linear solves' round-off only (1e-8). The block is 1e3 times stiffer than the discs so that the
  one-pair run is an independent answer up to the interaction through the block, which the
  one-pair run itself measures (the block's surface under the other pole); the tolerance is twice
  that interaction. Hertz's half-width within the Hertz suite's 3%.
* *Disc between plates*: statics fixes the loading plate's contact force, the floating disc's
  balance and the base reaction (1e-9); each pair's force on each of its bodies is within the
  solver's own imbalance bound of F (1e-2: the interpolation transfer is not conservative). The
  displacement-controlled run must give back F and the approach within the loop's stopping
  precision (gaps settled to 1e-5 h_c), expressed over the approach, and the same contact zone,
  node for node (its field is reported: the two runs' iterates differ, and their fields at the
  rim by more than the gap precision; the pairing is the same unslid one). Hertz's half-width (full model's force 2F) within 3%, the fit centred on the symmetry
  axis.
"""


def report_text(cases: list[MultiCase], checks: list[Check], records: dict, quick: bool, seconds: float) -> str:
    lines = [f"{'Quick subset' if quick else 'Full suite'}: {len(cases)} cases, {len(checks)} checks, "
             f"{sum(not c.passed for c in checks)} failed; wall time {seconds:.0f} s.", "",
             "| case | geo (level) | why | quick | exit statuses | solve s |", "|---|---|---|---|---|---|"]
    for case in cases:
        r = records[case.name]
        lines.append(f"| {case.name} | `{case.script}.geo` ({case.level}) | {case.why} | {'yes' if case.quick else ''} "
                     f"| {r.get('exit', r.get('error', ''))} | {r.get('seconds', math.nan):.2f} |")
    lines += checks_table(checks)
    lines += ["", DECISIONS]
    return "\n".join(lines)


def main() -> int:
    return standalone(__doc__, {c.name for c in CASES}, run_suite, "multi_body.json", BUILD)


if __name__ == "__main__":
    sys.exit(main())
