#!/usr/bin/python3
"""Gated sweep of flat contact: flat blocks pressed together and stiff flat punches on a block.

The curved-body sweep (``sweep.py``) never presses two flat faces together: there the contact zone
grows from a point, and its rim is where the answer is decided. Here the whole face is in contact
from the first load, its edges are corners of both bodies, and a stiff punch puts a pressure
singularity at its corners. A covering set of named cases (``CASES``), not a factorial: every value
of every parameter below appears at least once. E = 1000 for the lower block and for the block under
a punch, nu = 0.3 everywhere.

Family 1, two flat blocks stacked (``geo/flat_blocks_2d.geo``, ``geo/flat_blocks_3d.geo``): the
lower block's base held, the upper block's top pushed down by the approach d (0.1% to 3% of the
total height H_l + H_u), or the upper block meshed d into the lower one with nothing imposed
(``approach_by = "overlap"``). Blocks 2 x 0.5 + 0.5 (2D) and 1 x 1 x (0.5 + 0.5) (3D); the upper
block as wide, or 0.6 times as wide; as high, or half as high; E ratio 1 or 10. Supports
(``supports``): "clamped" (both ends clamped, the sides free), "rollers" (the same, and the sides
held normally), "sliding" (both ends held only vertically, pinned against the horizontal rigid
motions at points of a symmetry plane). Contact-face spacings h_u / h_l from 0.2 to 5
(non-matching meshes; 1: equal sizes). Primary "lower", "upper" or "auto".

Family 2, a stiff flat punch on a wider block (``geo/punch_2d.geo``, ``geo/punch_3d.geo``): the
block 2 x 1 (2D) or 2 x 2 x 1 (3D), its base clamped; the punch (half-width / radius 0.25, height
0.25) E ratio 1e3 or 1e4 times stiffer, its top pushed down by d (0.5% to 2% of the block's
height), its corners sharp or rounded (radius ``corner``). Primary "auto" (the block: the more
compliant body) or named.

References (each owes nothing to internodes; the tolerances are fixed here before any run):

* *symmetric blocks* (equal widths, heights and materials, both ends supported alike): the union of
  the two blocks solved by dolfinx as one body meshed conformingly (``flat_reference.union_solve``:
  the interface is a symmetry plane of the union, normal displacement uniform and shear stress
  zero, so the union solves the frictionless problem where it is compressive). Rows:
  ``premise: compression`` (the largest normal stress of the union's interface cells over the
  magnitude of their mean, tolerance 0: no tension anywhere on the interface);
  ``premise: P1 error`` (the union meshed at the case's coarser face spacing against the union at
  the reference spacing, h_min / 2 in 2D, h_min / 1.5 in 3D, relative force difference, tolerance
  0.005: the discretization alone takes at most half of the force tolerance, so a miss of the next
  row is the solver's); ``force`` (|P / P_ref - 1|, P the vertical contact force on the upper block,
  P_ref the union's force at the reference spacing, tolerance 0.01); ``interface`` (the largest
  distance of a contact-face node of either block, deformed, from the union's deformed interface at
  the same lateral position, over the approach d, tolerance 0.01).
* *asymmetric blocks* (elsewhere): ``agreement``: the same mesh solved with each body primary and
  each transfer (``transfer = "interpolation"`` and ``"conservative"``), four more solves, and the
  case's own configuration on a mesh with both face spacings halved (``refined``). A variant
  the solver vouches for (converged, accuracy report passed) is compared; one that ends with a
  named status or a failed accuracy report gives no answer and is listed, not compared. Figure
  (largest - smallest) / smallest vertical force over the vouched-for variants and the case's own
  run, tolerance 0.01; at least one vouched-for variant other than the case's own configuration is
  required (else nothing independent confirms the case's force: failed row, figure NaN).
* *punches*: the block alone in dolfinx under the punch's discrete face taken as rigid
  (``flat_reference.punch_solve``). Sharp corners: every node of the footprint ends in contact
  (``premise: whole face``, figure the fraction of footprint nodes not in contact, tolerance 0), so
  the reference is the block with the punch's footprint displaced by the punch's approach.
  Rounded corners: the contact edge is the reference's own, on the punch's P1 profile (each block
  node under the punch held on the plane of the punch facet below it, along that facet's normal,
  tangentially free: small sliding; a vertical constraint instead moved the force of the 2D
  rounded case with a 2% approach by 1.2%); ``premise: edge on the corner`` (the reference's
  outermost contact node lies on the rounded corner, beyond the flat face: else the case tests a
  sharp punch; tolerance 0). Rows: ``reference`` (the VI converged and its KKT check passed) and
  ``force`` (|P / P_ref - 1|, P the vertical contact force on the block, tolerance 0.01). The punch of the
  internodes run is 1e3 or 1e4 times stiffer, not rigid: its own compliance changes the force by
  about 1e-3 (E ratio 1e3), far inside the tolerance.

Every case also has ``mesh`` (the contact faces' measured mean edge lengths within 25% of the asked
spacings: the premise of the case, on the mesh gmsh made), ``status`` (converged: 0), ``solved``
and ``accuracy`` (the solver's two reports, ``suite.report_rows``: every entry present and passed,
flags consistent) and ``primary`` (an explicit primary honoured, "auto" reported as auto). A case
judged unsupported (``supported = False``) must be right, or end with one of the statuses it names
(``expect``; never "iteration-limit"): ``named failure`` row.

Usage:  /usr/bin/python3 validation/flat_sweep.py [--quick] [--binary PATH] [--cases NAME ...] [--out DIR]

Meshes, case files, outputs, logs and cached dolfinx references go to validation/build/flat_sweep/.
"""

from __future__ import annotations

import json
import math
import sys
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

VALIDATION = Path(__file__).resolve().parent
REPO = VALIDATION.parent

import flat_reference  # noqa: E402
from compare import Check  # noqa: E402
from contact_reference import ReferenceFailure  # noqa: E402
from suite import (checks_table, run_cases, standalone, Figure, MeshFailed, SuiteResult, body_table, case_toml, contact_table, json_safe, mesh_geo,
                   report_rows, run_solve,  # noqa: E402
                   solver_reports, surface_spacing, vouched)
from sweep import plot_summary, read_output, solved_primary, vertical_force  # noqa: E402

BUILD = VALIDATION / "build" / "flat_sweep"
YOUNGS_MODULUS = 1000.0  # the lower block's, and the block's under a punch
POISSON_RATIO = 0.3

# Geometry (module doc). Blocks: lower half-width, heights (the upper one times height_ratio).
BLOCKS = {2: {"W_l": 1.0, "H": 0.5}, 3: {"W_l": 0.5, "H": 0.5}}
# Punch on a block: block half-width and height, punch half-width / radius and height.
PUNCH = {"W": 1.0, "H": 1.0, "w": 0.25, "H_p": 0.25}
WIDTH_RATIO_NARROW = 0.6

# Tolerances, fixed before any run.
FORCE_TOLERANCE = 0.01
INTERFACE_TOLERANCE = 0.01  # of the approach
P1_PREMISE = 0.005  # the union's own discretization error at the coarser spacing
MESH_TOLERANCE = 0.25
AGREEMENT_TOLERANCE = 0.01
# Statuses that name a reason (an unsupported case may end with one of those it lists).
NAMED_STATUSES = ("not-solved", "cycling", "stalled", "unstable")


@dataclass(frozen=True)
class FlatCase:
    """One named case (module doc for every field)."""

    name: str
    dim: int
    kind: str  # "blocks" | "punch"
    approach: float  # d / total height (blocks) or d / the block's height (punch)
    h: float  # blocks: h_l, the lower face's spacing; punch: h_b, the block's spacing at the footprint
    spacing_ratio: float = 1.0  # blocks: h_u / h_l; punch: h_p / h_b
    primary: str = "auto"  # "auto" | "lower" | "upper" | "block" | "punch"
    supports: str = "clamped"  # blocks: "clamped" | "rollers" | "sliding"
    width_ratio: float = 1.0  # blocks: W_u / W_l
    height_ratio: float = 1.0  # blocks: H_u / H_l
    e_ratio: float = 1.0  # blocks: E_upper / E_lower; punch: E_punch / E_block
    approach_by: str = "imposed"  # "imposed" | "overlap" (blocks)
    corner: float = 0.0  # punch corner radius (0: sharp)
    quick: bool = False
    supported: bool = True
    expect: tuple = ()  # statuses an unsupported case may end with (subset of NAMED_STATUSES)
    timeout: float = 600.0
    why: str = ""

    @property
    def h_other(self) -> float:
        return self.h * self.spacing_ratio

    @property
    def heights(self) -> tuple[float, float]:
        if self.kind == "punch":
            return PUNCH["H"], PUNCH["H_p"]
        return BLOCKS[self.dim]["H"], BLOCKS[self.dim]["H"] * self.height_ratio

    @property
    def delta(self) -> float:
        height = sum(self.heights) if self.kind == "blocks" else PUNCH["H"]
        return float(f"{self.approach * height:.6g}")

    @property
    def gap(self) -> float:
        return -self.delta if self.approach_by == "overlap" else 0.0

    @property
    def imposed(self) -> float:
        return self.delta + self.gap

    @property
    def symmetric(self) -> bool:
        """Symmetric about the interface: the union is the reference (module doc)."""
        return (self.kind == "blocks" and self.width_ratio == 1 and self.height_ratio == 1
                and self.e_ratio == 1)

    def bodies(self) -> dict:
        """Role -> (body, candidate surface, support); the moving (upper) body first."""
        if self.kind == "punch":
            return {"punch": ("punch", "punch_contact", "punch_top"),
                    "block": ("block", "block_contact", "block_base")}
        return {"upper": ("upper", "upper_contact", "upper_top"), "lower": ("lower", "lower_contact", "lower_base")}

    def moduli(self) -> dict:
        first, second = self.bodies()
        return {first: YOUNGS_MODULUS * self.e_ratio, second: YOUNGS_MODULUS}

    def geo(self) -> tuple[str, dict]:
        if self.kind == "punch":
            parameters = {"h_b": round(self.h, 6), "h_p": round(self.h_other, 6)}
            if self.corner:
                parameters["rho"] = self.corner
        else:
            b = BLOCKS[self.dim]
            parameters = {"W_l": b["W_l"], "W_u": round(b["W_l"] * self.width_ratio, 6), "H_l": self.heights[0],
                          "H_u": self.heights[1], "h_l": round(self.h, 6), "h_u": round(self.h_other, 6)}
        if self.gap:
            parameters["gap"] = round(self.gap, 9)
        return f"{'punch' if self.kind == 'punch' else 'flat_blocks'}_{self.dim}d", parameters

    def parameters_text(self) -> str:
        how = "meshed overlapping, nothing imposed" if self.approach_by == "overlap" else "imposed"
        if self.kind == "punch":
            shape = f"corner radius {self.corner:g}" if self.corner else "sharp corners"
            return (f"{self.dim}D punch, {shape}, E ratio {self.e_ratio:g}, h_block {self.h:.4g}, h_punch / "
                    f"h_block {self.spacing_ratio:g}, d = {self.delta:g} ({self.approach:.1%} of H, {how}), "
                    f"primary {self.primary}")
        shape = []
        if self.width_ratio != 1:
            shape.append(f"W_u / W_l {self.width_ratio:g}")
        if self.height_ratio != 1:
            shape.append(f"H_u / H_l {self.height_ratio:g}")
        if self.e_ratio != 1:
            shape.append(f"E_u / E_l {self.e_ratio:g}")
        return (f"{self.dim}D blocks, {self.supports}, {', '.join(shape) or 'equal blocks'}, h_l {self.h:.4g}, "
                f"h_u / h_l {self.spacing_ratio:g}, d = {self.delta:g} ({self.approach:.1%} of H, {how}), "
                f"primary {self.primary}")


# The covering set.
CASES = (
    # --- two flat blocks, symmetric: the union is the reference --------------------------------
    FlatCase("2d-blocks-clamped-r0.2", 2, "blocks", 0.01, 0.05, 0.2, quick=True,
             why="clamped ends, the upper face 5 times finer; auto primary"),
    FlatCase("2d-blocks-clamped-r5-upper", 2, "blocks", 0.03, 0.01, 5.0, primary="upper",
             why="clamped ends, the upper face 5 times coarser and primary (explicit); 3% approach"),
    FlatCase("2d-blocks-rollers-r2-lower", 2, "blocks", 0.001, 0.025, 2.0, primary="lower", supports="rollers",
             why="sides on rollers (uniaxial strain), 0.1% approach; the finer lower face primary (explicit)"),
    FlatCase("2d-blocks-sliding-r0.5", 2, "blocks", 0.03, 0.05, 0.5, supports="sliding",
             why="ends free to slide (uniaxial stress), pinned at the axis; 3% approach; auto primary"),
    FlatCase("2d-blocks-overlap-r1", 2, "blocks", 0.01, 0.05, 1.0, primary="lower", approach_by="overlap",
             quick=True,
             why="meshed overlapping by 1% of the height (4 spacings), nothing imposed; equal sizes; the lower "
                 "primary (explicit)"),
    FlatCase("3d-blocks-rollers-r0.5", 3, "blocks", 0.01, 0.1, 0.5, supports="rollers",
             why="3D, sides on rollers, the upper face twice finer; auto primary"),
    FlatCase("3d-blocks-sliding-r2-upper", 3, "blocks", 0.001, 0.05, 2.0, primary="upper", supports="sliding",
             why="3D, ends free to slide, 0.1% approach, the twice coarser upper face primary (explicit)"),
    FlatCase("3d-blocks-clamped-r0.8-lower", 3, "blocks", 0.03, 0.05, 0.8, primary="lower",
             why="3D, clamped ends, 3% approach, the lower face primary (explicit)"),
    FlatCase("3d-blocks-overlap-r1.25", 3, "blocks", 0.005, 0.04, 1.25, approach_by="overlap",
             why="3D, clamped ends, meshed overlapping by 0.5% of the height, nothing imposed; auto primary"),
    # --- two flat blocks, asymmetric: the primaries and transfers must agree ------------------------
    FlatCase("2d-blocks-narrow-upper-r0.5", 2, "blocks", 0.01, 0.05, 0.5, width_ratio=WIDTH_RATIO_NARROW,
             why="the upper block 0.6 times as wide: its corners press into the lower face; auto primary"),
    FlatCase("2d-blocks-E10-short-r2", 2, "blocks", 0.01, 0.025, 2.0, height_ratio=0.5, e_ratio=10.0,
             supports="rollers", quick=True,
             why="the upper block 10 times stiffer and half as high, sides on rollers; auto primary"),
    FlatCase("3d-blocks-narrow-overlap-r1.5-lower", 3, "blocks", 0.01, 0.1, 0.667, width_ratio=WIDTH_RATIO_NARROW,
             approach_by="overlap", primary="lower", supported=False, expect=("not-solved",),
             why="unsupported: the wider face primary (explicit) under a block as stiff whose edges press into it: "
                 "the traction jumps at the secondary's edges, which the interpolation transfer does not carry in "
                 "balance and the conservative one spreads with tension; must end not-solved"),
    # --- stiff flat punches -------------------------------------------------------------------------
    FlatCase("2d-punch-sharp-E1e3", 2, "punch", 0.005, 0.0125, 0.8, e_ratio=1e3, quick=True,
             why="sharp corners, E ratio 1e3, 0.5% approach; auto primary"),
    FlatCase("2d-punch-sharp-E1e4-deep", 2, "punch", 0.02, 0.0125, 1.6, e_ratio=1e4,
             why="sharp corners, E ratio 1e4, 2% approach, the punch face coarser; auto primary"),
    FlatCase("2d-punch-rounded-E1e3-block", 2, "punch", 0.02, 0.0125, 0.8, e_ratio=1e3, corner=0.1,
             primary="block",
             why="rounded corners (radius 0.1), E ratio 1e3, 2% approach; the block primary (explicit)"),
    FlatCase("2d-punch-rounded-E1e4", 2, "punch", 0.01, 0.0125, 0.8, e_ratio=1e4, corner=0.1,
             why="rounded corners (radius 0.1), E ratio 1e4, 1% approach; auto primary"),
    FlatCase("3d-punch-sharp-E1e4", 3, "punch", 0.005, 0.04, 1.0, e_ratio=1e4,
             why="3D cylinder, sharp edge, E ratio 1e4, 0.5% approach; auto primary"),
    FlatCase("3d-punch-rounded-E1e3", 3, "punch", 0.01, 0.02, 1.0, e_ratio=1e3, corner=0.08,
             why="3D cylinder, rounded edge (radius 0.08, four block spacings), E ratio 1e3, 1% approach; auto "
                 "primary. At h_block 0.04 (two spacings per radius) the accuracy report refuses the answer: sag "
                 "estimate 1.8% for a force 1.4% below this mesh's"),
)


class RunFailed(RuntimeError):
    """Meshing, solving or reading failed; the message says which and why."""


# ---------------------------------------------------------------------------
# Meshes, case files, solves
# ---------------------------------------------------------------------------


def mesh(script: str, dim: int, parameters: dict) -> Path:
    name = script + "".join(f"_{k}{v:g}" for k, v in parameters.items()) + ".msh"
    try:
        return mesh_geo(script, dim, parameters, BUILD / "meshes" / name)
    except MeshFailed as error:
        raise RunFailed(str(error)) from error


def dirichlet(case: FlatCase) -> dict:
    """Body -> list of (group, {component: value}) (module doc, supports)."""
    d, v = case.dim, "uz" if case.dim == 3 else "uy"
    lateral = ["ux", "uy"][: d - 1]
    zero = dict.fromkeys(lateral + [v], 0.0)
    push = dict.fromkeys(lateral, 0.0) | {v: -case.imposed}
    if case.kind == "punch":
        return {"punch": [("punch_top", push)], "block": [("block_base", zero)]}
    result = {}
    for body, end, value in (("upper", "upper_top", -case.imposed), ("lower", "lower_base", 0.0)):
        rows = [(end, dict.fromkeys(lateral, 0.0) | {v: value})]
        if case.supports == "rollers":
            rows += ([(f"{body}_sides", {"ux": 0.0})] if d == 2 else
                     [(f"{body}_sides_x", {"ux": 0.0}), (f"{body}_sides_y", {"uy": 0.0})])
        elif case.supports == "sliding":
            rows = [(end, {v: value}), (f"{body}_pin", dict.fromkeys(lateral, 0.0))]
            if d == 3:
                rows.append((f"{body}_pin_axis", {"uy": 0.0}))
        result[body] = rows
    return result


def case_text(case: FlatCase, msh: Path, output: Path, primary: str | None = None,
              transfer: str | None = None) -> str:
    (moving, moving_surface, _), (fixed, fixed_surface, _) = case.bodies().values()
    primary = case.primary if primary is None else primary
    extra = {"transfer": transfer} if transfer else {}
    contact = contact_table((moving, fixed), (moving_surface, fixed_surface), primary, **extra)
    moduli = case.moduli()
    bodies = [body_table(body, moduli[body], POISSON_RATIO, rows) for body, rows in dirichlet(case).items()]
    comment = f"{case.name}: {case.parameters_text()} (written by validation/flat_sweep.py)"
    return case_toml(msh, output, contact, bodies, comment)


def solve(binary: Path, case: FlatCase, msh: Path, label: str = "", primary: str | None = None,
          transfer: str | None = None) -> tuple[Path, dict]:
    """Write the case and run internodes; (output folder, run record). A run that did not converge
    still writes its last iterate (a failed row, not a crash); no output at all is RunFailed."""
    folder = BUILD / (case.name + (f"-{label}" if label else ""))
    folder.mkdir(parents=True, exist_ok=True)
    output = folder / "internodes"
    toml = folder / "case.toml"
    toml.write_text(case_text(case, msh, output, primary, transfer))
    run = run_solve(binary, toml, output, case.timeout, folder / "log.txt")
    code, seconds = run.exit, run.seconds
    if not (output / "summary.json").is_file() or not (output / "solution.h5").is_file():
        raise RunFailed(f"internodes wrote no solution (exit {code}, {seconds:.1f} s): {run.tail()}")
    return output, {"seconds": seconds, "exit": code}


# ---------------------------------------------------------------------------
# References (cached in build/flat_sweep/references)
# ---------------------------------------------------------------------------


def _cached(name: str, stamp_data: dict, compute) -> dict:
    folder = BUILD / "references"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.json"
    if path.is_file():
        data = json.loads(path.read_text())
        if data.get("stamp") == stamp_data:
            return data
    data = compute() | {"stamp": stamp_data}
    path.write_text(json.dumps(json_safe(data)))
    return data


def union_reference(case: FlatCase, h: float) -> dict:
    """``flat_reference.union_solve`` of the case's blocks meshed as one body at spacing h, solved
    for a unit approach (cached) and scaled to the case's: the problem is linear."""
    b = BLOCKS[case.dim]
    parameters = {"union": 1, "W_l": b["W_l"], "H_l": case.heights[0], "H_u": case.heights[1],
                  "h_l": round(h, 6), "h_u": round(h, 6)}
    msh = mesh(f"flat_blocks_{case.dim}d", case.dim, parameters)
    stamp = {"mesh": json.loads(msh.with_suffix(".json").read_text()), "supports": case.supports,
             "delta": 1.0, "E": YOUNGS_MODULUS, "nu": POISSON_RATIO}
    unit = _cached(f"{msh.stem}_{case.supports}", stamp, lambda: flat_reference.union_solve(
        msh, case.dim, case.supports, 1.0, YOUNGS_MODULUS, POISSON_RATIO, b["W_l"], *case.heights))
    d = case.delta
    interface = unit["interface"]
    return unit | {"delta": d, "force": unit["force"] * d,
                   "interface": interface | {"deformed": (np.array(interface["deformed"]) * d).tolist(),
                                             "mean": interface["mean"] * d, "min": interface["min"] * d,
                                             "max": interface["max"] * d},
                   "interface_sigma_vv": {k: (v * d if k != "cells" else v)
                                          for k, v in unit["interface_sigma_vv"].items()}}


def punch_reference(case: FlatCase, msh: Path) -> dict:
    stamp = {"mesh": json.loads(msh.with_suffix(".json").read_text()), "delta": case.delta,
             "E": YOUNGS_MODULUS, "nu": POISSON_RATIO}
    return _cached(f"{msh.stem}_punch_delta{case.delta:g}", stamp, lambda: flat_reference.punch_solve(
        msh, case.dim, case.delta, YOUNGS_MODULUS, POISSON_RATIO, sharp=not case.corner))


# ---------------------------------------------------------------------------
# Checks
# ---------------------------------------------------------------------------


def mesh_check(case: FlatCase, msh: Path) -> tuple[Check, dict]:
    """The contact faces' mean edge lengths against the asked spacings (punch: within the footprint)."""
    if case.kind == "punch":
        within = PUNCH["w"]
        asked = {"block_contact": case.h, "punch_contact": case.h_other}
    else:
        within = 10.0
        asked = {"lower_contact": case.h, "upper_contact": case.h_other}
    measured = {g: surface_spacing(msh, g, case.dim, within) for g in asked}
    errors = [abs(measured[g] / asked[g] - 1) for g in asked]
    figure = max(errors) if all(map(math.isfinite, errors)) else math.nan
    return Check("mesh", case.name, figure, MESH_TOLERANCE, "; ".join(
        f"{g} {measured[g]:.4g} (asked {asked[g]:.4g})" for g in asked)), measured


def status_check(case: FlatCase, contact: dict) -> Check:
    status = contact.get("status")
    return Check("status", case.name, 0.0 if status == "converged" else 1.0, 0.0,
                 f"{status}, {len(contact.get('iterations', []))} iterations, primary {contact.get('primary')}, "
                 f"transfer {(contact.get('transfer') or {}).get('transfer')}")


def primary_check(case: FlatCase, contact: dict) -> Check:
    choice = contact.get("primary_choice") if isinstance(contact.get("primary_choice"), dict) else {}
    mode, solved = choice.get("mode"), contact.get("primary")
    if case.primary == "auto":
        ok = mode == "auto" and solved in case.bodies()
        note = f"auto chose {solved}: {choice.get('reason', '')}" if ok else f"asked auto; primary_choice {choice or 'missing'}"
    else:
        ok = mode == "explicit" and solved == case.primary
        note = f"asked {case.primary}, solved with {solved} ({mode or 'no primary_choice'})"
    return Check("primary", case.name, 0.0 if ok else 1.0, 0.0, note)


def named_failure_check(case: FlatCase, contact: dict) -> Check:
    """An unsupported case the solver did not vouch for: its status is one the case names."""
    status = contact.get("status")
    solved, accuracy = solver_reports(contact)
    failed = [c for c in (solved or {}).get("checks", []) + (accuracy or {}).get("indicators", [])
              if isinstance(c, dict) and c.get("passed") is False]
    named = status in case.expect and status in NAMED_STATUSES
    note = (f"expected one of {list(case.expect)}: {status}; "
            + "; ".join(f"{c.get('name')} {c.get('value'):.3g} > {c.get('tolerance'):.3g}" for c in failed))
    return Check("named failure", case.name, 0.0 if named else 1.0, 0.0, note)


def contact_force(out: dict, body: str, dim: int) -> float:
    if solved_primary(out) is None:
        raise RunFailed("summary.json contact has no 'primary'")
    return vertical_force(out, body, dim)


def face_nodes(out: dict, case: FlatCase) -> dict:
    """Body -> mask of its contact-face nodes (lower: x_v = 0; upper: x_v = gap)."""
    v = case.dim - 1
    x = out["geometry"]
    masks = {}
    for body, level in (("lower", 0.0), ("upper", case.gap)):
        on = out["node_body"] == out["body_names"].index(body)
        masks[body] = on & (np.abs(x[:, v] - level) <= 1e-9)
    return masks


def union_checks(case: FlatCase, out: dict, h: dict) -> tuple[list[Check], dict]:
    """Symmetric blocks against dolfinx's union (module doc)."""
    h_ref = min(case.h, case.h_other) / (2.0 if case.dim == 2 else 1.5)
    h_max = max(case.h, case.h_other)
    ref, coarse = union_reference(case, h_ref), union_reference(case, h_max)
    sigma = ref["interface_sigma_vv"]
    p1 = abs(coarse["force"] / ref["force"] - 1)
    checks = [
        Check("premise: compression", case.name, sigma["max"] / abs(sigma["mean"]), 0.0,
              f"largest sigma_vv of the union's {sigma['cells']} interface cells {sigma['max']:.4g}, mean "
              f"{sigma['mean']:.4g} (h {h_ref:.4g})"),
        Check("premise: P1 error", case.name, p1, P1_PREMISE,
              f"the union meshed at h {h_max:.4g}: P = {coarse['force']:.6g}; at h {h_ref:.4g}: {ref['force']:.6g} "
              f"({ref['num_nodes']} nodes)"),
    ]
    force = contact_force(out, "upper", case.dim)
    checks.append(Check("force", case.name, abs(force / ref["force"] - 1), FORCE_TOLERANCE,
                        f"P = {force:.6g} on the upper block, the union's {ref['force']:.6g} (h {h_ref:.4g}); "
                        f"on the lower block {contact_force(out, 'lower', case.dim):.6g}"))
    # the deformed contact faces against the union's deformed interface at the same lateral position
    v = case.dim - 1
    lateral_ref = np.array(ref["interface"]["lateral"])
    deformed_ref = np.array(ref["interface"]["deformed"])
    masks = face_nodes(out, case)
    worst, where = 0.0, ""
    for body, mask in masks.items():
        if not mask.any():
            raise RunFailed(f"no contact-face nodes of {body} found at its face level")
        x = out["geometry"][mask]
        ours = x[:, v] + out["displacement"][mask, v]
        if case.dim == 2:
            order = np.argsort(lateral_ref[:, 0])
            theirs = np.interp(x[:, 0], lateral_ref[order, 0], deformed_ref[order])
        else:
            from scipy.interpolate import LinearNDInterpolator, NearestNDInterpolator
            theirs = LinearNDInterpolator(lateral_ref, deformed_ref)(x[:, :2])
            missing = ~np.isfinite(theirs)
            if missing.any():
                theirs[missing] = NearestNDInterpolator(lateral_ref, deformed_ref)(x[missing, :2])
        distance = np.abs(ours - theirs)
        if distance.max() > worst:
            worst = float(distance.max())
            k = int(distance.argmax())
            where = f"{body} node at {np.round(x[k, :v], 4).tolist()}: {ours[k]:.6g} against {theirs[k]:.6g}"
    checks.append(Check("interface", case.name, worst / case.delta, INTERFACE_TOLERANCE,
                        f"largest distance {worst:.3e} of a contact-face node, deformed, from the union's interface "
                        f"({where}); the union's interface between {ref['interface']['min']:.6g} and "
                        f"{ref['interface']['max']:.6g}; d = {case.delta:g}"))
    return checks, {"force": force, "force_reference": ref["force"], "p1_error": p1, "interface_error": worst}


def agreement_check(binary: Path, case: FlatCase, msh: Path, out: dict) -> tuple[list[Check], dict]:
    """Both primaries and both transfers on the same mesh (module doc)."""
    forces = {"case": contact_force(out, "upper", case.dim)}
    problems = []
    records = {}
    for primary in ("lower", "upper"):
        for transfer in ("interpolation", "conservative"):
            label = f"{primary}-{transfer}"
            output, run = solve(binary, case, msh, label, primary, transfer)
            other = read_output(output)
            contact = other["contact"]
            records[label] = {"status": contact.get("status"), "seconds": run["seconds"],
                              "iterations": len(contact.get("iterations", []))}
            if not vouched(contact):
                problems.append(f"{label}: {contact.get('status')}, accuracy "
                                f"{(solver_reports(contact)[1] or {}).get('passed')}")
                continue
            forces[label] = contact_force(other, "upper", case.dim)
            records[label]["force"] = forces[label]
    # Another discretization of the same set-up: both face spacings halved, the case's own choices.
    refined = replace(case, h=case.h / 2)
    script, parameters = refined.geo()
    output, run = solve(binary, refined, mesh(script, case.dim, parameters), "refined")
    other = read_output(output)
    contact = other["contact"]
    records["refined"] = {"status": contact.get("status"), "seconds": run["seconds"],
                          "iterations": len(contact.get("iterations", []))}
    if vouched(contact):
        forces["refined"] = records["refined"]["force"] = contact_force(other, "upper", case.dim)
    else:
        problems.append(f"refined: {contact.get('status')}, accuracy {(solver_reports(contact)[1] or {}).get('passed')}")
    # Every variant is either vouched for, and then within the tolerance of the case's force, or
    # it ends with a named status or a failed accuracy report (an answer that says it is not to
    # be trusted is no answer to compare); at least one variant other than the case's own
    # configuration must be vouched for, or nothing independent confirms the case's force.
    own = f"{case.primary if case.primary != 'auto' else out['contact'].get('primary')}-" \
          f"{(out['contact'].get('transfer') or {}).get('transfer')}"
    others = [k for k in forces if k not in ("case", own)]
    values = list(forces.values())
    spread = (max(values) - min(values)) / min(values)
    note = ", ".join(f"{k} {p:.6g}" for k, p in forces.items())
    named = f"; named (not compared): {'; '.join(problems)}" if problems else ""
    if not others:
        return [Check("agreement", case.name, math.nan, AGREEMENT_TOLERANCE,
                      f"no variant other than the case's own ({own}) is vouched for{named}; forces {note}")], \
            {"agreement": records}
    return [Check("agreement", case.name, spread, AGREEMENT_TOLERANCE,
                  f"vertical force on the upper block: {note}{named}")], {"agreement": records, "spread": spread}


def punch_checks(case: FlatCase, msh: Path, out: dict) -> tuple[list[Check], dict]:
    ref = punch_reference(case, msh)
    ok = ref["kkt"]["passed"] and ref["snes"]["converged_reason"] > 0
    checks = [Check("reference", case.name, 0.0 if ok else 1.0, 0.0,
                    f"dolfinx VI: reason {ref['snes']['converged_reason']}, {ref['snes']['iterations']} its, KKT "
                    + ", ".join(f"{k} {v:.1e}" for k, v in ref["kkt"].items() if k != "passed")
                    + f"; {ref['nodes_in_contact']} of {ref['nodes_under_punch']} block nodes under the punch in "
                      f"contact, out to r = {ref['contact_radius']:.4g}")]
    if case.corner:
        flat_end, edge = PUNCH["w"] - case.corner, ref["contact_radius"]
        on_corner = flat_end + 1e-9 < edge <= PUNCH["w"] + 1e-9
        checks.append(Check("premise: edge on the corner", case.name, 0.0 if on_corner else 1.0, 0.0,
                            f"the reference's outermost contact node at r = {edge:.4g}; the flat face ends at "
                            f"{flat_end:.4g}, the rounded corner at {PUNCH['w']:g}"))
    else:
        missing = ref["flat_face_nodes"] - ref["flat_face_nodes_in_contact"]
        checks.append(Check("premise: whole face", case.name, missing / max(ref["flat_face_nodes"], 1), 0.0,
                            f"{ref['flat_face_nodes_in_contact']} of the {ref['flat_face_nodes']} footprint nodes "
                            f"in contact in the reference"))
    force = contact_force(out, "block", case.dim)
    checks.append(Check("force", case.name, abs(force / ref["force"] - 1), FORCE_TOLERANCE,
                        f"P = {force:.6g} on the block, dolfinx under the rigid punch {ref['force']:.6g}; on the "
                        f"punch {contact_force(out, 'punch', case.dim):.6g}"))
    return checks, {"force": force, "force_reference": ref["force"], "reference_contact_radius": ref["contact_radius"]}


# ---------------------------------------------------------------------------
# One case, the suite
# ---------------------------------------------------------------------------


def run_case(binary: Path, case: FlatCase) -> tuple[list[Check], dict]:
    """Mesh, reference, solve, checks. Anything that fails is a failed row, never a skip."""
    record: dict = {"parameters": asdict(case) | {"delta": case.delta, "gap": case.gap}}
    checks: list[Check] = []
    try:
        script, parameters = case.geo()
        msh = mesh(script, case.dim, parameters)
        check, measured = mesh_check(case, msh)
        checks.append(check)
        record["spacings"] = measured
        output, run = solve(binary, case, msh)
        record |= run
        out = read_output(output)
        contact = out["contact"]
        record |= {"status": contact.get("status"), "iterations": len(contact.get("iterations", [])),
                   "primary": contact.get("primary"), "transfer": (contact.get("transfer") or {}).get("transfer")}
        if not case.supported and not vouched(contact):
            checks += [named_failure_check(case, contact), primary_check(case, contact)]
            return checks, record
        checks += [status_check(case, contact), *report_rows(case.name, contact), primary_check(case, contact)]
        if case.kind == "punch":
            more, data = punch_checks(case, msh, out)
        elif case.symmetric:
            more, data = union_checks(case, out, measured)
        else:
            more, data = agreement_check(binary, case, msh, out)
        checks += more
        record |= data
    except (RunFailed, ReferenceFailure, OSError, KeyError, ValueError, TypeError, json.JSONDecodeError) as error:
        checks.append(Check("run", case.name, math.nan, 0.0, f"{type(error).__name__}: {error}"))
        record["error"] = f"{type(error).__name__}: {error}"
    return checks, record


def run_suite(binary: Path, quick: bool, out_dir: Path, names: list[str] | None = None) -> SuiteResult:
    start = time.perf_counter()
    out_dir.mkdir(parents=True, exist_ok=True)
    cases = [c for c in CASES if (c.quick or not quick) and (not names or c.name in names)]
    checks, records = run_cases(cases, lambda case: run_case(binary, case), lambda case: case.parameters_text())
    figures = []
    summary_png = out_dir / "flat_sweep_summary.png"
    if plot_summary(cases, checks, records, summary_png):
        figures.append(Figure("Flat contact: every check's figure over its tolerance per case (a point above 1 is "
                              "a miss, NaN plotted at the top), iterations and solve time per case", summary_png))
    seconds = time.perf_counter() - start
    text = report_text(cases, checks, records, quick, seconds)
    return SuiteResult("Sweep, flat contact: flat blocks pressed together and stiff flat punches (gate)", checks,
                       figures, text, {"quick": quick, "seconds": seconds, "cases": json_safe(records)})


DECISIONS = """\
**Decisions** (module doc of `validation/flat_sweep.py`; fixed before any run):

* *Symmetric blocks* are judged against dolfinx's union of the two blocks, meshed conformingly, at
  a finer spacing than either face (h_min / 2 in 2D, h_min / 1.5 in 3D), with two premises: the
  union is in compression on its whole interface (else the frictionless answer is not the
  union's), and the union meshed at the case's coarser spacing is within 0.5% of the reference
  (the mesh alone takes at most half of the 1% force tolerance; clamped corners converge like
  h^1.4).
* *Asymmetric blocks* (the upper one narrower, or shorter and stiffer) have no closed-form or
  one-body reference: the combinations of primary and transfer the solver vouches for must agree
  within 1% on the force, and at least one besides the case's own configuration must be vouched
  for (a variant named by the solver is listed, not compared).
* *Punches* are judged against the block alone under the punch's own P1 face taken as rigid (the
  punch is 1e3 or 1e4 times stiffer); for sharp corners the reference's contact set is the whole
  footprint (checked), i.e. the footprint prescribed as the punch's approach.
"""


def report_text(cases: list[FlatCase], checks: list[Check], records: dict, quick: bool, seconds: float) -> str:
    lines = [f"{'Quick subset' if quick else 'Full flat sweep'}: {len(cases)} cases, {len(checks)} checks, "
             f"{sum(not c.passed for c in checks)} failed; wall time {seconds:.0f} s.",
             "", f"**Cases** (E = {YOUNGS_MODULUS:g} for the lower block and the block under a punch, nu = "
                 f"{POISSON_RATIO}; H the total height of the blocks, or the block's under a punch):", "",
             "| case | parameters | why | quick | reference | status | iterations | solve s |",
             "|---|---|---|---|---|---|---|---|"]
    for case in cases:
        r = records[case.name]
        reference = ("rigid punch (dolfinx)" if case.kind == "punch" else
                     "union (dolfinx)" if case.symmetric else "primaries and transfers agree")
        lines.append(f"| {case.name} | {case.parameters_text()} | {case.why} | {'yes' if case.quick else ''} "
                     f"| {reference} | {r.get('status', r.get('error', ''))} | {r.get('iterations', '')} "
                     f"| {r.get('seconds', math.nan):.1f} |")
    lines += checks_table(checks)
    lines += ["", DECISIONS]
    return "\n".join(lines)


def main() -> int:
    return standalone(__doc__, {c.name for c in CASES}, run_suite, "flat_sweep.json", BUILD)


if __name__ == "__main__":
    sys.exit(main())
