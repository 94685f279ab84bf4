#!/usr/bin/python3
"""Gated sweep of contact at edges and corners: a held-out family, each run right or named.

The other sweeps put the contact zone where both meshes were made for it: a pole at the origin, a
punch whose rim carries the same nodes as the block's circle under it. Here the edges of one body
fall anywhere on the other body's mesh: a stiff square punch shifted off the block's mesh lines
(sharp or filleted edges), the lowest edge of a tilted elastic cube on a stiff block, the lowest
corner of a tilted square (2D). A block node just beyond a punch's edge faces no facet of the
punch; a solver that measures it against the plane of the face's last facet makes it active where
the block bulges, and certifies a force several percent too high (the defect this family was made
to catch, fixed by ``4636835 gap: ...``).

Families (``FAMILIES``), each at two spacing ratios (r = h_stiff / h_compliant, 0.7 and 1.4) and two
or three approaches d, each solved with the compliant body primary, the stiff body primary and
"auto" (three runs of one mesh and one reference). E = 1000 for the compliant body and 1e6 for the
stiff one (E ratio 1e3), nu = 0.3:

* ``square-sharp``: ``geo/square_punch_3d.geo``, a square punch of half-width 0.3 (12 block
  spacings across at h_block 0.05) and height H_p = 0.5, its axis shifted by (0.0137, 0.0071), on
  the block [-1, 1]^2 x [-1, 0] clamped at its base; the punch's top pushed down by d = 0.1%, 0.5%,
  2% of H_p. Reference: the block under the rigid sharp punch (``edge_reference.punch_solve``, the
  punch's P1 face): every block node under the footprint touches, the others are free.
* ``square-fillet``: the same punch with its lower and vertical edges filleted, radius 0.1 (two
  block spacings; the fillets meshed at rho / 16 = 0.00625), d = 0.5% and 2% of H_p. Reference: the block under
  the exact filleted punch (the analytic surface, checked against the punch's mesh nodes), the
  contact edge the VI's.
* ``cube-edge``: ``geo/tilted_cube_3d.geo``, an elastic cube of side a = 0.4 turned by 20 degrees
  about x (its lowest edge along x, the faces there sloping by 20 and 70 degrees) and by 17 degrees
  about z (the edge along no axis), the edge's middle at (0.0031, 0.0057), on a stiff block
  [-0.6, 0.6]^2 x [-0.5, 0] clamped at its base; the cube's two upper faces pushed down by d = 1%,
  2%, 4% of a; both meshes refined to h_cube = 0.01 (and r h_cube on the block) within 0.04 of the
  edge. Reference: the cube on a rigid plane (``edge_reference.plane_solve``).
* ``square-corner-2d``: ``geo/tilted_square_2d.geo``, an elastic square of side a = 0.4 turned by 30
  degrees (its lowest corner at x = 0.0013, the sides there sloping by 30 and 60 degrees) on a stiff
  block [-0.6, 0.6] x [-0.5, 0]; the square's two upper sides pushed down by d = 1%, 2%, 4% of a;
  h_square = 0.001 within 0.05 of the corner (at 0.002 and d = 0.5% and 1% the zone was under 1.5
  spacings across and every run ended named, auto too: outside the supported range). Reference:
  the square on a rigid plane. The stiff block (1e3) stands for the plane.
* ``square-corner-2d-equal``: the same meshes and approaches with the block as compliant as the
  square (E = 1000 for both). Reference: the two elastic bodies on the same mesh
  (``edge_reference.two_body_solve``: dolfinx's stiffness matrices, node to segment from the
  square's nodes onto the block's facets, the gap measured on the deformed surfaces, solved to
  convergence; premise row ``premise: candidates``, which also gives the answer of the same
  discrete problem along the loop's path, ``update="primal-dual"``: where it differs, the problem
  has several solutions, as two of the six cases do, by -3.2% and -0.7%, ``docs/method.md`` 4.1).
  The loop holds the corner's node in the crater it digs by two walls (``docs/method.md`` 3.2,
  4.1): auto must be RIGHT where the reference's zone spans at least ``RESOLVED_ZONE`` spacings
  of the square (``Family.auto_resolved_from``), RIGHT or NAMED below, and no run may be
  certified wrong. Since the discrete problem can have several solutions, an exit-0 answer
  outside the bounds of the reference is also judged against the reference started from it
  (``two_body_solve(start_from=...)``: the solution nearest ours, which must converge).
* ``cube-edge-equal``: the ``cube-edge`` meshes with the block as compliant as the cube (E = 1000
  for both), d = 1% of a only. Reference: the two elastic bodies on the same mesh, node to triangle
  (``edge_reference.two_body_solve_3d``, checked against the rigid plane with the block made rigid;
  premise row ``premise: candidates``). At 2% its iteration did not settle within 400 steps
  (block ratio 0.7: the largest change of a displacement still 2e-2 d a step, the edge sliding
  across the groove it digs), so the family holds the approach where the reference is known. The
  zone is the edge's line, one node across: RIGHT or NAMED, auto's too (auto takes the cube and
  sends its force node to facet along the block's smoothed normals, ``docs/method.md`` 3.6).

Each run is classified (``classify``) from its exit status and its answer:

* RIGHT: exit 0 (solved, accuracy report passed) and the force on the compliant body within 1% of
  the reference (``FORCE_TOLERANCE``; for a 2D two-body reference, or of the reference started from
  our answer) and the contact zone within one spacing (``ZONE_TOLERANCE``,
  ``zone_distance``: each deformed active node of the primary with pressure within one spacing,
  laterally, of a reference contact node, and each reference contact node within one spacing of
  one of ours; a node's spacing is the longer of the longest contact-surface edge at it and the
  other set's mean spacing, so that one row of nodes more or less at the rim is one spacing);
* NAMED: exit 2 (not solved) or 3 (solved, accuracy report failed): the solver said so;
* WRONG: exit 0 outside either bound: a certified wrong answer;
* ERROR: exit 1, a timeout, no output, or an exit status that contradicts summary.json.

Gate rows per run: ``<primary>: right or named`` (figure 0 for RIGHT or NAMED, 1 for WRONG or ERROR)
for an explicit primary, ``auto: right`` (0 only for RIGHT: "auto not right" otherwise) for auto
(``auto: right or named`` in a family outside what the default supports),
and ``primary`` (an explicit primary honoured, auto reported as auto). Per case: ``mesh`` (the
contact faces' measured mean edge lengths within 25% of the asked spacings), ``reference`` (the VI
converged, its KKT conditions hold) and a premise: ``premise: whole footprint`` (sharp: every block
node under the footprint in contact in the reference, none outside), ``premise: fillet surface``
(the punch's contact nodes on the analytic fillet within 1e-6 rho) and ``premise: P1 fillet`` (the
block under the punch's own P1 face within 0.3% of the block under the exact fillet: the faceting
of the punch, which no solver can undo, takes at most 0.3% of the force, under a third of its
tolerance; with the fillets meshed at rho / 4 it took 2.9% at d = 0.5%, hence rho / 16). The plane
references' contact zone width is in the ``reference`` row's note (at 1% of a the cube's zone is
one row of nodes along the edge: an edge contact, kept).

The quick subset (``QUICK``, ``run.py --quick``): the six families at r = 1.4, one approach each
(the sharp punch at 0.5%, the case that showed the defect; the equal cube's edge at 1%).

Usage:  /usr/bin/python3 validation/edge_sweep.py [--quick] [--binary PATH] [--cases NAME ...] [--out DIR]

Meshes, case files, outputs, logs and cached dolfinx references go to validation/build/edge_sweep/.
"""

from __future__ import annotations

import functools
import json
import math
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

VALIDATION = Path(__file__).resolve().parent
REPO = VALIDATION.parent

import edge_reference  # noqa: E402
from compare import Check  # noqa: E402
from contact_reference import ReferenceFailure  # noqa: E402
from flat_sweep import RunFailed  # noqa: E402
from suite import (checks_table, run_cases, standalone, MeshFailed, SuiteResult, body_table, case_toml, contact_table, group_edges, json_safe, mesh_geo,  # noqa: E402
                   run_solve, solver_reports, vouched)
from sweep import loaded, read_output, solved_primary, vertical_force  # noqa: E402

BUILD = VALIDATION / "build" / "edge_sweep"
E_COMPLIANT = 1000.0
E_RATIO = 1e3
POISSON_RATIO = 0.3

# Tolerances, fixed before any run.
FORCE_TOLERANCE = 0.01
# A contact zone narrower than this many spacings is not resolved (the stiff square's corner at
# h = 0.002 and 0.5% or 1%: under 1.5 spacings across, every run named by the resolution indicator).
RESOLVED_ZONE = 1.5
ZONE_TOLERANCE = 1.0  # spacings
MESH_TOLERANCE = 0.25
FILLET_TOLERANCE = 1e-6  # of rho
P1_FILLET_PREMISE = 0.003  # the punch's P1 face against the exact fillet, relative force
RATIOS = (0.7, 1.4)


@dataclass(frozen=True)
class Family:
    """One geometry (module doc)."""

    name: str
    dim: int
    script: str
    compliant: str
    stiff: str
    h: float  # the compliant body's spacing at the contact
    length: float  # d = approach x length (H_p of a punch, a of a cube / square)
    approaches: tuple
    geo: tuple = ()  # fixed geo parameters (name, value)
    e_ratio: float = E_RATIO  # E_stiff / E_compliant
    auto_supported: bool = True  # "auto" must be RIGHT (else RIGHT or NAMED, like an explicit primary)
    # ... where the reference's contact zone is at least this many spacings of the compliant body
    # across (below, RIGHT or NAMED: the solver's resolution indicator names such a zone)
    auto_resolved_from: float = 0.0

    @property
    def bodies(self) -> tuple[str, str]:
        """(moving, fixed): the moving body's top is pushed down, the fixed one's base clamped."""
        return (self.stiff, self.compliant) if self.compliant == "block" else (self.compliant, self.stiff)


FAMILIES = {
    f.name: f for f in (
        Family("square-sharp", 3, "square_punch_3d", "block", "punch", 0.05, 0.5, (0.001, 0.005, 0.02),
               (("rho", 0.0),)),
        Family("square-fillet", 3, "square_punch_3d", "block", "punch", 0.05, 0.5, (0.005, 0.02),
               (("rho", 0.1), ("h_fillet", 0.00625))),
        Family("cube-edge", 3, "tilted_cube_3d", "cube", "block", 0.01, 0.4, (0.01, 0.02, 0.04)),
        Family("square-corner-2d", 2, "tilted_square_2d", "square", "block", 0.001, 0.4, (0.01, 0.02, 0.04)),
        Family("square-corner-2d-equal", 2, "tilted_square_2d", "square", "block", 0.001, 0.4, (0.01, 0.02, 0.04),
               e_ratio=1.0, auto_resolved_from=RESOLVED_ZONE),
        Family("cube-edge-equal", 3, "tilted_cube_3d", "cube", "block", 0.01, 0.4, (0.01,),
               e_ratio=1.0, auto_supported=False),
    )
}
# The geo scripts' defaults the sweep relies on: the square punch's half-width and shift; the cube's
# side, turn about z and edge middle, the refined distance around its edge; the square's corner and
# its refined distance.
PUNCH = {"w": 0.3, "sx": 0.0137, "sy": 0.0071}
CUBE = {"a": 0.4, "phi": 17.0, "sx": 0.0031, "sy": 0.0057, "r_c": 0.04}
CORNER = {"sx": 0.0013, "r_c": 0.05}


def near_feature(family: Family, x: np.ndarray) -> np.ndarray:
    """Mask of the points x (n, 3) where the mesh check measures spacings: under the punch's flat face
    (a margin of 0.02 inside it), within r_c of the cube's lowest edge (between its ends), within r_c
    of the square's lowest corner."""
    if family.script == "square_punch_3d":
        half = PUNCH["w"] - dict(family.geo).get("rho", 0.0) - 0.02
        return (np.abs(x[:, 0] - PUNCH["sx"]) <= half) & (np.abs(x[:, 1] - PUNCH["sy"]) <= half)
    if family.script == "tilted_cube_3d":
        f = math.radians(CUBE["phi"])
        along = np.array([math.cos(f), math.sin(f), 0.0])
        rel = x - np.array([CUBE["sx"], CUBE["sy"], 0.0])
        t = rel @ along
        return (np.linalg.norm(rel - np.outer(t, along), axis=1) <= CUBE["r_c"]) & (np.abs(t) <= CUBE["a"] / 2)
    return np.hypot(x[:, 0] - CORNER["sx"], x[:, 1]) <= CORNER["r_c"]


def feature_spacing(msh: Path, group: str, family: Family) -> float:
    """Mean length of the edges of a boundary group with both ends ``near_feature``."""
    try:
        x, edges = group_edges(msh, group, family.dim)
    except ValueError as error:
        raise RunFailed(str(error)) from error
    near = edges[near_feature(family, x)[edges].all(axis=1)]
    if len(near) == 0:
        return math.nan
    return float(np.linalg.norm(x[near[:, 0]] - x[near[:, 1]], axis=1).mean())


@dataclass(frozen=True)
class EdgeCase:
    """One mesh and approach of a family; three runs (primaries)."""

    family: str
    ratio: float  # h_stiff / h_compliant
    approach: float
    quick: bool = False

    @property
    def f(self) -> Family:
        return FAMILIES[self.family]

    @property
    def name(self) -> str:
        return f"{self.family}-r{self.ratio:g}-d{self.approach * 100:g}%"

    @property
    def delta(self) -> float:
        return float(f"{self.approach * self.f.length:.6g}")

    @property
    def spacings(self) -> dict:
        """Contact group -> asked spacing."""
        f = self.f
        return {f"{f.compliant}_contact": f.h, f"{f.stiff}_contact": round(f.h * self.ratio, 6)}

    @property
    def primaries(self) -> tuple[str, ...]:
        return (self.f.compliant, self.f.stiff, "auto")

    def geo_parameters(self) -> dict:
        f = self.f
        hs = round(f.h * self.ratio, 6)
        if f.script == "square_punch_3d":
            return {"h_b": f.h, "h_p": hs, **dict(f.geo)}
        return {"h_c": f.h, "h_b": hs, **dict(f.geo)}

    def text(self) -> str:
        f = self.f
        return (f"{f.dim}D {f.name}, h_{f.compliant} {f.h:g}, h_{f.stiff} / h_{f.compliant} {self.ratio:g}, "
                f"d = {self.delta:g} ({self.approach:.1%} of {f.length:g})")


QUICK = {("square-sharp", 1.4, 0.005), ("square-fillet", 1.4, 0.02), ("cube-edge", 1.4, 0.02),
         ("square-corner-2d", 1.4, 0.02), ("square-corner-2d-equal", 1.4, 0.02), ("cube-edge-equal", 1.4, 0.01)}
CASES = tuple(EdgeCase(f.name, r, d, (f.name, r, d) in QUICK)
              for f in FAMILIES.values() for r in RATIOS for d in f.approaches)


# ---------------------------------------------------------------------------
# Meshes, case files, solves, references
# ---------------------------------------------------------------------------


def mesh(case: EdgeCase) -> Path:
    parameters = case.geo_parameters()
    name = case.f.script + "".join(f"_{k}{v:g}" for k, v in parameters.items()) + ".msh"
    try:
        return mesh_geo(case.f.script, case.f.dim, parameters, BUILD / "meshes" / name)
    except MeshFailed as error:
        raise RunFailed(str(error)) from error


def case_text(case: EdgeCase, msh: Path, output: Path, primary: str) -> str:
    f = case.f
    moving, fixed = f.bodies
    lateral = ["ux", "uy"][: f.dim - 1]
    v = "uz" if f.dim == 3 else "uy"
    contact = contact_table((moving, fixed), (f"{moving}_contact", f"{fixed}_contact"), primary)
    moduli = {f.compliant: E_COMPLIANT, f.stiff: E_COMPLIANT * f.e_ratio}
    bodies = [body_table(moving, moduli[moving], POISSON_RATIO,
                         [(f"{moving}_top", dict.fromkeys(lateral, 0.0) | {v: -case.delta})]),
              body_table(fixed, moduli[fixed], POISSON_RATIO,
                         [(f"{fixed}_base", dict.fromkeys(lateral + [v], 0.0))])]
    return case_toml(msh, output, contact, bodies,
                     f"{case.name}, primary {primary}: {case.text()} (written by validation/edge_sweep.py)")


def solve(binary: Path, case: EdgeCase, msh: Path, primary: str, timeout: float = 900.0) -> tuple[Path, dict]:
    folder = BUILD / "runs" / f"{case.name}-{primary}"
    folder.mkdir(parents=True, exist_ok=True)
    output = folder / "internodes"
    toml = folder / "case.toml"
    toml.write_text(case_text(case, msh, output, primary))
    run = run_solve(binary, toml, output, timeout, folder / "log.txt")
    return output, {"exit": run.exit, "seconds": run.seconds, "tail": run.tail()}


def reference(case: EdgeCase, msh: Path) -> dict:
    """The case's dolfinx reference (module doc), cached per mesh, approach and kind."""
    f = case.f
    rho = dict(f.geo).get("rho", 0.0)
    kind = ("two-body" if f.e_ratio == 1.0 else "plane") if f.compliant != "block" else ("fillet" if rho else "sharp")
    stamp = {"mesh": json.loads(msh.with_suffix(".json").read_text()), "delta": case.delta, "kind": kind,
             "E": E_COMPLIANT, "nu": POISSON_RATIO, "version": 2}
    folder = BUILD / "references"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{msh.stem}_{kind}_delta{case.delta:g}.json"
    if path.is_file():
        data = json.loads(path.read_text())
        if data.get("stamp") == stamp:
            return data
    if kind == "two-body":
        if f.dim == 2:
            data = edge_reference.two_body_solve(msh, case.delta, E_COMPLIANT, POISSON_RATIO)
            other = edge_reference.two_body_solve(msh, case.delta, E_COMPLIANT, POISSON_RATIO, update="primal-dual")
            data["other_path"] = {"force": other["force"], "converged": edge_reference.converged(other),
                                  "nodes_in_contact": other["nodes_in_contact"]}
        else:
            data = edge_reference.two_body_solve_3d(msh, case.delta, E_COMPLIANT, POISSON_RATIO)
    elif kind == "plane":
        data = edge_reference.plane_solve(msh, f.dim, f.compliant, case.delta, E_COMPLIANT, POISSON_RATIO)
    elif kind == "sharp":
        data = edge_reference.punch_solve(msh, case.delta, E_COMPLIANT, POISSON_RATIO, footprint=PUNCH)
    else:
        exact = PUNCH | {"rho": rho}
        data = edge_reference.punch_solve(msh, case.delta, E_COMPLIANT, POISSON_RATIO, exact=exact)
        p1 = edge_reference.punch_solve(msh, case.delta, E_COMPLIANT, POISSON_RATIO)
        data["p1_face_force"] = p1["force"]
        data["fillet_surface_error"] = edge_reference.fillet_surface_error(msh, **exact)
    data["stamp"] = stamp
    path.write_text(json.dumps(json_safe(data)))
    return data


# ---------------------------------------------------------------------------
# Checks and the classification
# ---------------------------------------------------------------------------


def case_checks(case: EdgeCase, msh: Path, ref: dict) -> tuple[list[Check], dict]:
    """Mesh, reference and premise rows of a case; the measured spacings."""
    f = case.f
    measured = {g: feature_spacing(msh, g, f) for g in case.spacings}
    errors = [abs(measured[g] / h - 1) for g, h in case.spacings.items()]
    checks = [Check("mesh", case.name, max(errors) if all(map(math.isfinite, errors)) else math.nan,
                    MESH_TOLERANCE, "; ".join(f"{g} {measured[g]:.4g} (asked {h:.4g})"
                                              for g, h in case.spacings.items())),
              Check("reference", case.name, 0.0 if edge_reference.converged(ref) else 1.0, 0.0,
                    f"dolfinx VI: reason {ref['snes']['converged_reason']}, {ref['snes']['iterations']} its, KKT "
                    + ", ".join(f"{k} {v:.1e}" for k, v in ref["kkt"].items() if k != "passed")
                    + f"; {ref['nodes_in_contact']} of {ref['nodes_constrained']} candidate nodes in contact, "
                      f"P_ref = {ref['force']:.6g}")]
    h = measured[f"{f.compliant}_contact"]
    if "footprint_nodes" in ref:
        missing = ref["footprint_nodes"] - ref["footprint_nodes_in_contact"] + ref["in_contact_outside_footprint"]
        checks.append(Check("premise: whole footprint", case.name, missing / max(ref["footprint_nodes"], 1), 0.0,
                            f"{ref['footprint_nodes_in_contact']} of the {ref['footprint_nodes']} block nodes under "
                            f"the footprint in contact, {ref['in_contact_outside_footprint']} outside"))
    elif "fillet_surface_error" in ref:
        checks.append(Check("premise: fillet surface", case.name, ref["fillet_surface_error"], FILLET_TOLERANCE,
                            f"largest distance of a punch contact node from the exact fillet / rho; the contact "
                            f"reaches {ref['contact_beyond_flat'] / h:.2f} block spacings onto the fillet"))
        checks.append(Check("premise: P1 fillet", case.name, abs(ref["p1_face_force"] / ref["force"] - 1),
                            P1_FILLET_PREMISE,
                            f"the punch's own P1 face as the rigid obstacle: P = {ref['p1_face_force']:.6g}, "
                            f"against {ref['force']:.6g} for the exact fillet (the faceting of the punch takes at "
                            f"most {P1_FILLET_PREMISE:.1%} of the force tolerance)"))
    else:
        if "uncovered_penetration" in ref:
            checks.append(Check("premise: candidates", case.name, ref["uncovered_penetration"], 0.0,
                                f"the deepest {f.compliant} contact node outside the reference's candidates below "
                                f"the deformed block, over h; the {'corner' if f.dim == 2 else 'edge'} slid "
                                f"{ref['corner_slide_over_h']:.2f} h; small "
                                f"sliding (paired in the reference configuration) P = {ref['force_small_sliding']:.6g}"
                                + other_path_note(ref)))
        width = zone_width(ref, f.dim)
        checks[-1].note += (f"; the contact zone {width:.4g} across ({width / h:.2f} spacings of {f.compliant}) at "
                            f"its narrowest section")
    return checks, measured


def other_path_note(ref: dict) -> str:
    """The same discrete problem solved along the loop's path (``two_body_solve(update="primal-dual")``):
    where both answers hold their KKT conditions and differ, the problem has several solutions, and
    their difference is how close any solver of it can be held to the reference."""
    other = ref.get("other_path")
    if other is None:
        return ""
    if not other["converged"]:
        return "; along the primal-dual path the reference did not converge"
    if abs(other["force"] / ref["force"] - 1) <= 1e-5:
        return f"; the same along the primal-dual path (P = {other['force']:.6g})"
    return (f"; along the primal-dual path another solution, P = {other['force']:.6g} "
            f"({other['force'] / ref['force'] - 1:+.2%}, {other['nodes_in_contact']} nodes in contact)")


def zone_width(ref: dict, dim: int) -> float:
    """Width of the reference's contact zone across the edge / corner: in 2D its extent; in 3D its
    extent across the zone's long axis (principal axes of the contact nodes' lateral positions)."""
    x = np.array(ref["contact_deformed"])[:, : dim - 1]
    if len(x) < 2:
        return 0.0
    if dim == 2:
        return float(np.ptp(x[:, 0]))
    centred = x - x.mean(axis=0)
    _, _, axes = np.linalg.svd(centred, full_matrices=False)
    return float(np.ptp(centred @ axes[1]))


@functools.lru_cache(maxsize=16)
def local_spacing(msh: Path, group: str, dim: int) -> dict:
    """gmsh node tag -> the longest edge of the boundary group ``group`` at that node."""
    x, edges = group_edges(msh, group, dim)
    length = np.linalg.norm(x[edges[:, 0]] - x[edges[:, 1]], axis=1)
    longest = np.zeros(len(x))
    np.maximum.at(longest, edges[:, 0], length)
    np.maximum.at(longest, edges[:, 1], length)
    return {int(t): float(longest[t]) for t in np.unique(edges)}


def zone_distance(out: dict, body: str, ref: dict, case: EdgeCase, msh: Path, measured: dict) -> tuple[float, float]:
    """(ours -> reference, reference -> ours), in spacings: for each deformed loaded active node of
    ``body`` the lateral distance to the nearest reference contact node, and back, each over the
    larger of the node's own spacing (the longest contact-surface edge at it: one row of nodes more
    or less at the rim is one spacing) and the other set's mean spacing; the largest of each."""
    import h5py
    from scipy.spatial import cKDTree

    f = case.f
    with h5py.File(out["output"] / "solution.h5", "r") as h5:
        node_tag = h5["mesh/node_tag"][()]
    on = loaded(out, body, "contact_pressure")
    ours = (out["geometry"][on] + out["displacement"][on])[:, : f.dim - 1]
    theirs = np.array(ref["contact_deformed"])[:, : f.dim - 1]
    if len(ours) == 0 or len(theirs) == 0:
        return math.inf, math.inf
    ours_local = local_spacing(msh, f"{body}_contact", f.dim)
    ref_local = local_spacing(msh, f"{f.compliant}_contact", f.dim)
    h_ours, h_ref = measured[f"{body}_contact"], measured[f"{f.compliant}_contact"]
    scale_ours = np.maximum([ours_local.get(int(t), h_ours) for t in node_tag[on]], h_ref)
    scale_ref = np.maximum([ref_local.get(int(t), h_ref) for t in ref["contact_tags"]], h_ours)
    extra = cKDTree(theirs).query(ours)[0] / scale_ours
    missing = cKDTree(ours).query(theirs)[0] / scale_ref
    return float(extra.max()), float(missing.max())


def classify(case: EdgeCase, msh: Path, primary: str, run: dict, out: dict | None, ref: dict,
             measured: dict) -> dict:
    """RIGHT / NAMED / WRONG / ERROR (module doc) with its figures."""
    f = case.f
    record = {"primary_asked": primary, "exit": run["exit"], "seconds": run["seconds"],
              "zone_spacings": zone_width(ref, f.dim) / measured[f"{f.compliant}_contact"]}
    if out is None:
        return record | {"class": "ERROR", "why": f"no output (exit {run['exit']}): {run['tail']}"}
    contact = out["contact"]
    solved, accuracy = solver_reports(contact)
    failed = [c.get("name") for c in (solved or {}).get("checks", []) + (accuracy or {}).get("indicators", [])
              if isinstance(c, dict) and c.get("passed") is False]
    record |= {"status": contact.get("status"), "primary": solved_primary(out), "failed": failed,
               "iterations": len(contact.get("iterations", []))}
    try:
        force = vertical_force(out, f.compliant, f.dim)
        record["force"] = force
        record["force_error"] = force / ref["force"] - 1
        extra, missing = zone_distance(out, record["primary"], ref, case, msh, measured)
        record |= {"zone_extra": extra, "zone_missing": missing}
    except (RunFailed, KeyError, ValueError) as error:
        record["why"] = f"{type(error).__name__}: {error}"
    if run["exit"] in (2, 3):
        consistent = not vouched(contact)
        return record | {"class": "NAMED" if consistent else "ERROR",
                         "why": f"{contact.get('status')}; failed: {', '.join(failed) or 'none'}"
                                + ("" if consistent else "; the exit status contradicts summary.json")}
    if run["exit"] != 0 or not vouched(contact) or "force_error" not in record:
        return record | {"class": "ERROR", "why": record.get("why", f"exit {run['exit']}, status "
                                                                  f"{contact.get('status')}: {run['tail']}")}
    zone = max(record["zone_extra"], record["zone_missing"])
    if not math.isfinite(zone):
        return record | {"class": "ERROR", "why": f"the contact zone could not be compared (spacings {measured})"}
    right = abs(record["force_error"]) <= FORCE_TOLERANCE and zone <= ZONE_TOLERANCE
    why = f"force {record['force_error']:+.2%}, zone {zone:.2f} spacings"
    if not right and f.dim == 2 and f.e_ratio == 1.0:
        # The discrete problem may have several solutions (module doc): the one nearest ours.
        nearest = edge_reference.two_body_solve(msh, case.delta, E_COMPLIANT, POISSON_RATIO,
                                                start_from=solution_displacements(out))
        error = record["force"] / nearest["force"] - 1
        near_zone = max(zone_distance(out, record["primary"], nearest, case, msh, measured))
        record |= {"nearest_force": nearest["force"], "nearest_force_error": error}
        right = (edge_reference.converged(nearest) and abs(error) <= FORCE_TOLERANCE
                 and near_zone <= ZONE_TOLERANCE)
        why += (f"; the reference started from this answer {'converges' if edge_reference.converged(nearest) else 'does not converge'} "
                f"to P = {nearest['force']:.6g} ({nearest['force'] / ref['force'] - 1:+.2%} from the reference from rest): "
                f"force {error:+.2%}, zone {near_zone:.2f} spacings from it")
    return record | {"class": "RIGHT" if right else "WRONG", "why": why}


def solution_displacements(out: dict) -> dict:
    """Our answer's displacement at every node, ``{gmsh node tag: (u_x, u_y)}``."""
    import h5py

    with h5py.File(out["output"] / "solution.h5", "r") as h5:
        tags = h5["mesh/node_tag"][()]
        u = h5["fields/displacement"][()]
    return {int(t): (float(v[0]), float(v[1])) for t, v in zip(tags, u)}


def run_checks(case: EdgeCase, record: dict) -> list[Check]:
    """The gate rows of one run (module doc)."""
    label = f"{case.name} [{record['primary_asked']}]"
    klass = record["class"]
    figures = ""
    if "force_error" in record:
        figures = (f"P = {record['force']:.6g} ({record['force_error']:+.3%} against the reference), zone "
                   f"{record.get('zone_extra', math.nan):.2f} / {record.get('zone_missing', math.nan):.2f} spacings "
                   f"(ours beyond / reference missed); ")
    note = (f"{klass}: exit {record['exit']}, {record.get('status')}, primary {record.get('primary')}; {figures}"
            f"{record.get('why', '')}; {record['seconds']:.1f} s")
    resolved = record.get("zone_spacings", math.inf) >= case.f.auto_resolved_from
    if record["primary_asked"] == "auto" and not (case.f.auto_supported and resolved):
        rows = [Check("auto: right or named", label, 0.0 if klass in ("RIGHT", "NAMED") else 1.0, 0.0, note)]
    elif record["primary_asked"] == "auto":
        rows = [Check("auto: right", label, 0.0 if klass == "RIGHT" else 1.0, 0.0,
                      note if klass == "RIGHT" else "auto not right: " + note)]
    else:
        rows = [Check(f"{record['primary_asked']}: right or named", label,
                      0.0 if klass in ("RIGHT", "NAMED") else 1.0, 0.0, note)]
    if record.get("primary") is not None or klass != "ERROR":
        asked = record["primary_asked"]
        ok = record.get("primary") in case.f.bodies if asked == "auto" else record.get("primary") == asked
        rows.append(Check("primary", label, 0.0 if ok else 1.0, 0.0, f"asked {asked}, solved with "
                                                                      f"{record.get('primary')}"))
    return rows


# ---------------------------------------------------------------------------
# One case, the suite
# ---------------------------------------------------------------------------


def run_case(binary: Path, case: EdgeCase) -> tuple[list[Check], dict]:
    """Mesh, reference, the three runs, the checks. Anything that fails is a failed row, never a skip."""
    record: dict = {"parameters": asdict(case) | {"delta": case.delta, "name": case.name}, "runs": {}}
    checks: list[Check] = []
    try:
        msh = mesh(case)
        ref = reference(case, msh)
        more, measured = case_checks(case, msh, ref)
        checks += more
        record |= {"spacings": measured, "reference": {k: v for k, v in ref.items()
                                                       if k not in ("contact_deformed", "contact_tags", "stamp")}}
        for primary in case.primaries:
            output, run = solve(binary, case, msh, primary)
            try:
                out = read_output(output) if (output / "summary.json").is_file() else None
                if out is not None:
                    out["output"] = output
            except (RunFailed, OSError, KeyError, ValueError, json.JSONDecodeError) as error:
                out, run["tail"] = None, f"{type(error).__name__}: {error}"
            result = classify(case, msh, primary, run, out, ref, measured)
            record["runs"][primary] = result
            checks += run_checks(case, result)
            print(f"    {primary}: {result['class']} ({result.get('why', '')}), {run['seconds']:.1f} s", flush=True)
    except (RunFailed, ReferenceFailure, OSError, KeyError, ValueError, TypeError, json.JSONDecodeError) as error:
        checks.append(Check("run", case.name, math.nan, 0.0, f"{type(error).__name__}: {error}"))
        record["error"] = f"{type(error).__name__}: {error}"
    return checks, record


def counts(records: dict) -> dict:
    """Runs per class, auto runs not right, worst force error of the exit-0 runs."""
    runs = [(name, r) for name, rec in records.items() for r in rec.get("runs", {}).values()]
    tally = {k: sum(r["class"] == k for _, r in runs) for k in ("RIGHT", "NAMED", "WRONG", "ERROR")}
    exit0 = [(abs(r["force_error"]), name, r) for name, r in runs if r["exit"] == 0 and "force_error" in r]
    worst = max(exit0, key=lambda t: t[0], default=None)
    return tally | {"runs": len(runs), "auto_not_right": [f"{name} ({r['class']})" for name, r in runs
                                                          if r["primary_asked"] == "auto" and r["class"] != "RIGHT"],
                    "worst_exit0": (f"{worst[2]['force_error']:+.2%} ({worst[1]}, {worst[2]['primary_asked']})"
                                    if worst else "none")}


def run_suite(binary: Path, quick: bool, out_dir: Path, names: list[str] | None = None) -> SuiteResult:
    start = time.perf_counter()
    out_dir.mkdir(parents=True, exist_ok=True)
    cases = [c for c in CASES if (c.quick or not quick) and (not names or c.name in names or c.family in names)]
    checks, records = run_cases(cases, lambda case: run_case(binary, case), lambda case: case.text())
    seconds = time.perf_counter() - start
    tally = counts(records)
    text = report_text(cases, checks, records, quick, seconds, tally)
    return SuiteResult("Sweep, edges and corners: stiff square punches, a tilted cube's edge, a tilted square's "
                       "corner (gate)", checks, [], text,
                       {"quick": quick, "seconds": seconds, "counts": tally, "cases": json_safe(records)})


DECISIONS = """\
**Decisions** (module doc of `validation/edge_sweep.py`; fixed before any run):

* The stiff body (E ratio 1e3) is taken as rigid in every reference; its compliance moves the force
  by about 1e-3, a tenth of the force tolerance.
* The edges of one body fall off the other's mesh lines: the punch is shifted by (0.0137, 0.0071)
  off the block's axis and the block's top face is not split under it; the cube's edge is turned
  by 17 degrees about the vertical and shifted; the square's corner is at x = 0.0013.
* The contact zone is compared as point sets (the primary's active nodes with pressure against the
  reference's contact nodes, deformed, lateral plane), each node's distance to the other set in
  units of its own spacing (the longest contact-surface edge at it, at least the other set's mean
  spacing): one row of nodes more or less at the rim passes; a node one spacing beyond the
  footprint passes this row too, and the force row is the one that sees what it does.
* A run that ends with exit 2 or 3 is NAMED (acceptable) for an explicit primary; "auto" must be
  RIGHT (the default has to answer, or the family is outside what the default supports: the row
  says "auto not right").
"""


def report_text(cases: list[EdgeCase], checks: list[Check], records: dict, quick: bool, seconds: float,
                tally: dict) -> str:
    lines = [f"{'Quick subset' if quick else 'Full edge sweep'}: {len(cases)} cases, {tally['runs']} runs, "
             f"{len(checks)} checks, {sum(not c.passed for c in checks)} failed; wall time {seconds:.0f} s.", "",
             f"Runs: {tally['RIGHT']} RIGHT, {tally['NAMED']} NAMED, {tally['WRONG']} WRONG, {tally['ERROR']} ERROR; "
             f"auto not right: {', '.join(tally['auto_not_right']) or 'none'}; largest force error of an exit-0 "
             f"run: {tally['worst_exit0']}.", "",
             f"**Runs** (E = {E_COMPLIANT:g} for the compliant body, {E_COMPLIANT * E_RATIO:g} for the stiff one, "
             f"nu = {POISSON_RATIO}; force error against the dolfinx reference on the compliant body's mesh; zone: "
             "ours beyond / reference missed, in spacings):", "",
             "| case | quick | P_ref | primary | solved with | exit | status | force error | zone | class | s |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for case in cases:
        rec = records[case.name]
        if "error" in rec and not rec.get("runs"):
            lines.append(f"| {case.name} | {'yes' if case.quick else ''} | | | | | | | | ERROR: {rec['error']} | |")
            continue
        for primary, r in rec["runs"].items():
            fe = f"{r['force_error']:+.2%}" if "force_error" in r else ""
            zone = (f"{r['zone_extra']:.2f} / {r['zone_missing']:.2f}" if "zone_extra" in r else "")
            lines.append(f"| {case.name} | {'yes' if case.quick else ''} | {rec['reference']['force']:.5g} | {primary} "
                         f"| {r.get('primary', '')} | {r['exit']} | {r.get('status', '')}"
                         f"{' (' + ', '.join(r['failed']) + ')' if r.get('failed') else ''} | {fe} | {zone} "
                         f"| {'**' + r['class'] + '**' if r['class'] in ('WRONG', 'ERROR') else r['class']} "
                         f"| {r['seconds']:.1f} |")
    lines += checks_table(checks)
    lines += ["", DECISIONS]
    return "\n".join(lines)


def main() -> int:
    return standalone(__doc__, {c.name for c in CASES} | set(FAMILIES), run_suite, "edge_sweep.json", BUILD, binary=True)


if __name__ == "__main__":
    sys.exit(main())
