#!/usr/bin/python3
"""Independent dolfinx references for flat faces in contact (the flat family of ``flat_sweep.py``).

Two references, both computed by dolfinx (0.5.2) from the gmsh meshes, with nothing taken from
internodes:

* ``union_solve``: two equal flat blocks pressed together (``geo/flat_blocks_*.geo``). When the
  set-up is symmetric about the interface (equal widths, heights and materials, both ends supported
  alike), the plane of the interface is a plane of symmetry of the union of the two blocks: its
  normal displacement is uniform (the ends' mean) and its shear stress vanishes, so the union's
  solution satisfies the frictionless contact conditions, provided its normal stress on that plane
  is compressive everywhere. The frictionless answer is then the union's: one body of total height
  H_l + H_u, meshed conformingly (``union = 1``), the same supports, solved as one elastic body
  (P1, plane strain in 2D, sparse Cholesky). Returned: the force P through it (the top's vertical
  reaction, checked against the base's), the deformed height of its interface nodes, and the
  largest normal stress sigma_vv of the cells on the interface (the premise: compressive).
  Supports (``SUPPORTS``): "clamped" (base clamped, top displaced straight down, sides free);
  "rollers" (the same and the sides held normally); "sliding" (base and top held only vertically,
  pinned against the horizontal rigid motions at the points the geo script names).
* ``punch_solve``: a block under a rigid punch (``geo/punch_*.geo``). The block of the two-body mesh
  (exactly its gmsh nodes and cells), turned upside down (``contact_reference.turned_mesh``), is
  pressed by ``delta`` onto the punch's contact surface taken as a rigid obstacle: every node of the
  block's top face whose lateral position lies under the punch's discrete (P1) face is held on the
  plane of the punch's facet there, n . u >= -g0 (n the facet's normal, g0 the node's initial
  distance to that plane; small sliding, frictionless: the tangential components are free), by the
  bound-constrained solver of ``contact_reference.RigidFlatContact`` in coordinates rotated to n
  (PETSc SNES ``vinewtonrsls``, KKT checked). For a sharp punch every footprint node ends in contact: this is the block with the
  punch's footprint prescribed as the punch's approach, the vertical displacement only
  (frictionless). For rounded corners the contact edge is the solution's. The punch of the
  internodes run is 1e3 to 1e4 times stiffer than the block, not rigid.

Usage:
  /usr/bin/python3 validation/flat_reference.py union MESH.msh --supports clamped --delta 0.01 --W 1 --H_l 0.5 --H_u 0.5
  /usr/bin/python3 validation/flat_reference.py punch MESH.msh --delta 0.005
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np


from contact_reference import RigidFlatContact, obstacle_below, read_body, turned_mesh  # noqa: E402
from dolfinx_reference import Body, ReferenceFailure, ReferenceModel, solve_constrained  # noqa: E402

SUPPORTS = ("clamped", "rollers", "sliding")
# A node of the sharp punch's footprint is in contact if its gap is <= GAP_TOLERANCE delta.
GAP_TOLERANCE = 1e-9


def _on(x: np.ndarray, value: float, scale: float) -> np.ndarray:
    return np.abs(x - value) <= 1e-9 * scale


def union_solve(msh: Path, dim: int, supports: str, delta: float, youngs_modulus: float, poisson_ratio: float,
                half_width: float, height_lower: float, height_upper: float) -> dict:
    """The union body of ``msh`` (physical group ``union``), base at -H_l clamped / held, top at H_u
    moved down by ``delta`` (module doc); force, interface and its stresses."""
    if supports not in SUPPORTS:
        raise ReferenceFailure(f"supports '{supports}' is not one of {SUPPORTS}")
    start = time.perf_counter()
    body = read_body(msh, "union", ["interface"])
    x = body.x
    model = ReferenceModel(msh, {"union": x})
    material = Body("union", youngs_modulus, poisson_ratio)
    K = model.stiffness(material)
    n, v = len(x), dim - 1
    scale = max(np.ptp(x, axis=0).max(), 1.0)
    base, top = _on(x[:, v], -height_lower, scale), _on(x[:, v], height_upper, scale)
    interface = _on(x[:, v], 0.0, scale)
    if not (base.any() and top.any() and interface.any()):
        raise ReferenceFailure(f"{msh}: no base, top or interface nodes at -{height_lower}, {height_upper}, 0")
    g = np.full(n * dim, np.nan)

    def hold(nodes: np.ndarray, component: int, value: float) -> None:
        index = np.flatnonzero(nodes)
        if len(index) == 0:
            raise ReferenceFailure(f"{msh}: a support selects no node (component {component})")
        g[dim * index + component] = value

    hold(base, v, 0.0)
    hold(top, v, -delta)
    lateral = range(dim - 1)
    if supports in ("clamped", "rollers"):
        for c in lateral:
            hold(base, c, 0.0)
            hold(top, c, 0.0)
    if supports == "rollers":
        for c in lateral:
            hold(_on(np.abs(x[:, c]), half_width, scale), c, 0.0)
    if supports == "sliding":
        for level in (-height_lower, height_upper):
            centre = _on(x[:, v], level, scale) & (np.linalg.norm(x[:, list(lateral)], axis=1) <= 1e-9 * scale)
            for c in lateral:
                hold(centre, c, 0.0)
            if dim == 3:
                axis = (_on(x[:, v], level, scale) & _on(x[:, 0], half_width / 2, scale)
                        & _on(x[:, 1], 0.0, scale))
                hold(axis, 1, 0.0)
    u = solve_constrained(K, np.zeros(n * dim), g, f"{msh}: union")
    r = (K @ u).reshape(-1, dim)
    u = u.reshape(-1, dim)
    force = float(-r[top, v].sum())
    balance = float(abs(force - r[base, v].sum()) / abs(force))
    deformed = x[interface, v] + u[interface, v]
    # normal stress of the cells with a facet on the interface, both halves
    strain, stress = model._cell_tensors(u.ravel(), material)
    cells = model.local_cells("union")
    on_interface = interface[cells].sum(axis=1) >= dim
    sigma_vv = stress[on_interface, 3 * v + v]
    return {
        "mesh": str(msh), "dimension": dim, "supports": supports, "delta": delta, "E": youngs_modulus,
        "nu": poisson_ratio, "num_nodes": n, "force": force, "force_balance": balance,
        "interface": {"lateral": x[interface][:, list(lateral)].tolist(), "deformed": deformed.tolist(),
                      "mean": float(deformed.mean()), "min": float(deformed.min()), "max": float(deformed.max())},
        "interface_sigma_vv": {"max": float(sigma_vv.max()), "mean": float(sigma_vv.mean()),
                               "cells": int(on_interface.sum())},
        "seconds": time.perf_counter() - start,
    }


def punch_solve(msh: Path, dim: int, delta: float, youngs_modulus: float, poisson_ratio: float,
                sharp: bool) -> dict:
    """The block of ``msh`` under its punch taken as rigid (module doc); force and contact set."""
    start = time.perf_counter()
    turned = turned_mesh(msh, dim)
    block = read_body(turned, "block", ["block_contact", "block_base"])
    punch = read_body(turned, "punch", ["punch_contact"])
    facets = punch.x[punch.facets["punch_contact"]]
    model = RigidFlatContact(block, "block_contact", "block_base", youngs_modulus, poisson_ratio,
                             obstacle=lambda points: obstacle_below(facets, dim, points))
    solution = model.solve(delta)
    v = dim - 1
    bounded = model.contact_nodes[model.bounded]
    normals = model.normals[model.bounded]
    gap = model.height[model.bounded] + (solution.u[bounded] * normals).sum(axis=1)
    reaction = solution.reaction[bounded]
    force = float(reaction[:, v].sum())
    top_reaction = float(solution.reaction[model.top_nodes, v].sum())
    in_contact = (gap <= GAP_TOLERANCE * delta) & ((reaction * normals).sum(axis=1) > 0)
    # under the punch's flat face: a horizontal facet, touching at the start
    flat = (normals[:, v] > 1 - 1e-12) & (model.height[model.bounded] <= 1e-12)
    lateral = [c for c in range(dim) if c != v]
    r = np.linalg.norm(block.x[bounded][:, lateral], axis=1)
    return {
        "mesh": str(msh), "dimension": dim, "delta": delta, "E": youngs_modulus, "nu": poisson_ratio,
        "sharp": sharp, "num_nodes": int(block.num_nodes), "force": force,
        "force_balance": float(abs(force + top_reaction) / force),
        "nodes_under_punch": int(len(bounded)), "nodes_in_contact": int(in_contact.sum()),
        "flat_face_nodes": int(flat.sum()), "flat_face_nodes_in_contact": int((flat & in_contact).sum()),
        "contact_radius": float(r[in_contact].max()) if in_contact.any() else 0.0,
        "snes": {"iterations": solution.iterations, "converged_reason": solution.reason},
        "kkt": solution.kkt, "seconds": time.perf_counter() - start,
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    union = sub.add_parser("union", help="the union body of a flat_blocks mesh made with union = 1")
    union.add_argument("mesh", type=Path)
    union.add_argument("--supports", choices=SUPPORTS, default="clamped")
    union.add_argument("--delta", type=float, required=True)
    union.add_argument("--W", type=float, required=True, help="half-width")
    union.add_argument("--H_l", type=float, required=True)
    union.add_argument("--H_u", type=float, required=True)
    punch = sub.add_parser("punch", help="the block of a punch mesh under the punch taken as rigid")
    punch.add_argument("mesh", type=Path)
    punch.add_argument("--delta", type=float, required=True)
    punch.add_argument("--sharp", action="store_true")
    for p in (union, punch):
        p.add_argument("--E", type=float, default=1000.0)
        p.add_argument("--nu", type=float, default=0.3)
    args = parser.parse_args(argv)
    import gmsh
    from dolfinx_reference import _gmsh_model
    with _gmsh_model(args.mesh):
        dim = gmsh.model.getDimension()
    if args.command == "union":
        data = union_solve(args.mesh, dim, args.supports, args.delta, args.E, args.nu, args.W, args.H_l, args.H_u)
        data.pop("interface")
    else:
        data = punch_solve(args.mesh, dim, args.delta, args.E, args.nu, args.sharp)
    print(json.dumps(data, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
