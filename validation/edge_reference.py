#!/usr/bin/python3
"""Independent dolfinx references for contact at edges and corners (``edge_sweep.py``).

Every reference is computed by dolfinx (0.5.2) on exactly the gmsh nodes and cells of the compliant
body of the two-body mesh the internodes run reads, with nothing taken from internodes. The stiff
body of the internodes run (1e3 times stiffer) is taken as rigid. The bound-constrained solver is
``contact_reference.RigidFlatContact`` (PETSc SNES ``vinewtonrsls``: frictionless node-to-surface
contact, n . u >= -g0 at each candidate node, tangential components free; its KKT conditions are
checked on the returned solution).

* ``punch_solve``: the block of ``geo/square_punch_3d.geo`` under the punch taken as rigid. The mesh
  is turned upside down (``contact_reference.turned_mesh``) and the block pressed by ``delta`` onto
  the punch's lower surface:
  - ``exact=None``: the punch's own P1 face (``contact_reference.obstacle_below``: each block top
    node under a punch facet held on that facet's plane). With sharp edges the face is flat and its
    outline exact, so this is the rigid sharp punch: every block node under the footprint touches
    and the others are free (``premise: whole footprint``).
  - ``exact={"w", "rho", "sx", "sy"}``: the exact filleted punch, the square of half-width
    w - rho grown by a ball of radius rho (what OpenCASCADE's fillets of the geo script make, checked
    by ``fillet_surface_error``): each block top node's gap is its distance to that surface,
    |P - C| - rho, C the closest point of the core square (at height rho), and n = (P - C) / |P - C|.
    The contact edge is the solution's (an active-set / VI solve on the block nodes).
* ``plane_solve``: the compliant body of ``geo/tilted_cube_3d.geo`` (the cube) or
  ``geo/tilted_square_2d.geo`` (the square) pressed by ``delta`` (its top faces moved down, lateral
  components held) onto the rigid plane x_v = 0 that stands for the stiff block's top; the contact
  set is the solution's.
* ``two_body_solve``: the square of ``geo/tilted_square_2d.geo`` and the block, both elastic and of
  the same material (the stiff body is not taken as rigid here): node to segment from the square's
  contact nodes onto the block's facets, dolfinx's stiffness matrices, Newton steps on the gap
  measured on the deformed surfaces, each step's linear complementarity problem solved exactly
  (NNLS). Checked: with the block made rigid (``block_modulus`` 1e12) it gives ``plane_solve``'s force to
  7e-10 (1.65370693 at h 0.001, d = 0.008).
* ``two_body_solve_3d``: the same for the cube of ``geo/tilted_cube_3d.geo`` and the block, node to
  triangle, a row for every facet around the closest one that lies wholly above its plane (the
  groove the edge digs).
* ``prescribed_footprint``: the sharp punch's reference a second way, without a contact solver: the
  block alone, its top nodes under the footprint moved down by delta (tangentially free), one linear
  solve. It must equal ``punch_solve`` (every footprint node touches, the rest are free).

Each returns the force on the body, the contact nodes (gmsh tags, deformed positions in the frame of
the two-body mesh), the solver's convergence and KKT figures.

Usage:
  /usr/bin/python3 validation/edge_reference.py punch MESH.msh --delta 0.0025 [--rho 0.1 --w 0.3 --sx .. --sy ..]
  /usr/bin/python3 validation/edge_reference.py plane MESH.msh --delta 0.004 --body cube
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from contact_reference import (GAP_TOLERANCE, ReferenceFailure, RigidFlatContact, obstacle_below, read_body,  # noqa: E402
                               turned_mesh)
from dolfinx_reference import solve_constrained  # noqa: E402


def _turned_back(x: np.ndarray) -> np.ndarray:
    """Coordinates of the turned mesh (3D: y, z -> -y, -z) in the frame of the two-body mesh."""
    out = np.array(x, float, copy=True)
    out[:, 1:3] *= -1
    return out


def exact_fillet(points: np.ndarray, w: float, rho: float, sx: float, sy: float, turned: bool = True):
    """(g0, n) of ``points`` (k, 3) against the exact filleted punch (module doc). ``turned``: the
    points and the punch in the turned frame (punch below, pointing up at z = 0 of its face, its axis
    at (sx, -sy)); else in the mesh's frame (punch above, axis (sx, sy), n pointing down)."""
    p = np.asarray(points, float)
    cy = -sy if turned else sy
    core = w - rho
    q = np.empty_like(p)
    q[:, 0] = sx + np.clip(p[:, 0] - sx, -core, core)
    q[:, 1] = cy + np.clip(p[:, 1] - cy, -core, core)
    q[:, 2] = -rho if turned else rho
    v = p - q
    lateral = np.hypot(v[:, 0], v[:, 1])
    distance = np.linalg.norm(v, axis=1)
    gap = np.where(lateral < rho, distance - rho, np.inf)
    normals = np.zeros((len(p), 3))
    normals[:, 2] = 1.0 if turned else -1.0
    under = np.isfinite(gap)
    normals[under] = v[under] / distance[under, None]
    return gap, normals


def fillet_surface_error(msh: Path, w: float, rho: float, sx: float, sy: float) -> float:
    """Largest distance of a node of the punch's meshed contact surface from the exact filleted
    surface of ``exact_fillet`` (mesh frame), over rho: the premise that the analytic surface is the
    one gmsh meshed."""
    punch = read_body(msh, "punch", ["punch_contact"])
    nodes = np.unique(punch.facets["punch_contact"])
    x = punch.x[nodes]
    core = w - rho
    q = np.empty_like(x)
    q[:, 0] = sx + np.clip(x[:, 0] - sx, -core, core)
    q[:, 1] = sy + np.clip(x[:, 1] - sy, -core, core)
    q[:, 2] = rho
    distance = np.linalg.norm(x - q, axis=1)
    # the flat face lies at z = 0 (distance rho from the core plane), the fillet on the grown ball
    return float(np.abs(distance - rho).max() / rho)


def _solve(model: RigidFlatContact, delta: float) -> tuple:
    solution = model.solve(delta)
    bounded = model.contact_nodes[model.bounded]
    normals = model.normals[model.bounded] if model.rotation is not None else \
        np.tile(np.eye(model.dim)[model.v], (len(bounded), 1))
    gap = model.height[model.bounded] + (solution.u[bounded] * normals).sum(axis=1)
    reaction = solution.reaction[bounded]
    contact = (gap <= GAP_TOLERANCE * delta) & ((reaction * normals).sum(axis=1) > 0)
    return solution, bounded, contact, reaction


def _record(model: RigidFlatContact, solution, bounded, contact, reaction, delta: float, start: float,
            turned: bool) -> dict:
    v = model.dim - 1
    force = float(reaction[:, v].sum())
    top_reaction = float(solution.reaction[model.top_nodes, v].sum())
    nodes = bounded[contact]
    deformed = model.body.x[nodes] + np.pad(solution.u[nodes], ((0, 0), (0, 3 - model.dim)))
    if turned:
        deformed = _turned_back(deformed)
    return {
        "delta": delta, "num_nodes": int(model.body.num_nodes), "force": force,
        "force_balance": float(abs(force + top_reaction) / abs(force)) if force else float("nan"),
        "nodes_constrained": int(len(bounded)), "nodes_in_contact": int(contact.sum()),
        "contact_tags": model.body.node_tags[nodes].astype(int).tolist(),
        "contact_deformed": deformed[:, :3].tolist(),
        "snes": {"iterations": solution.iterations, "converged_reason": solution.reason},
        "kkt": solution.kkt, "seconds": time.perf_counter() - start,
    }


def punch_solve(msh: Path, delta: float, youngs_modulus: float, poisson_ratio: float,
                exact: dict | None = None, footprint: dict | None = None) -> dict:
    """The block of ``msh`` under its punch taken as rigid (module doc). ``footprint`` {"w", "sx",
    "sy"}: also count the block top nodes strictly inside the square footprint and those of them in
    contact (the sharp punch's premise)."""
    start = time.perf_counter()
    turned = turned_mesh(msh, 3)
    block = read_body(turned, "block", ["block_contact", "block_base"])
    if exact is None:
        punch = read_body(turned, "punch", ["punch_contact"])
        facets = punch.x[punch.facets["punch_contact"]]

        def obstacle(points):
            return obstacle_below(facets, 3, points)
    else:
        def obstacle(points):
            return exact_fillet(points, exact["w"], exact["rho"], exact["sx"], exact["sy"])
    model = RigidFlatContact(block, "block_contact", "block_base", youngs_modulus, poisson_ratio,
                             obstacle=obstacle)
    solution, bounded, contact, reaction = _solve(model, delta)
    record = _record(model, solution, bounded, contact, reaction, delta, start, turned=True)
    if footprint is not None:
        x = _turned_back(block.x[bounded])
        inside = ((np.abs(x[:, 0] - footprint["sx"]) < footprint["w"] - 1e-9)
                  & (np.abs(x[:, 1] - footprint["sy"]) < footprint["w"] - 1e-9))
        record["footprint_nodes"] = int(inside.sum())
        record["footprint_nodes_in_contact"] = int((inside & contact).sum())
        record["in_contact_outside_footprint"] = int((~inside & contact).sum())
    if exact is not None:
        # how far onto the fillet the contact reaches: the largest lateral distance of a contact
        # node from the flat face (0: the flat face only)
        x = _turned_back(block.x[bounded[contact]])
        core = exact["w"] - exact["rho"]
        beyond = np.hypot(np.maximum(np.abs(x[:, 0] - exact["sx"]) - core, 0),
                          np.maximum(np.abs(x[:, 1] - exact["sy"]) - core, 0))
        record["contact_beyond_flat"] = float(beyond.max()) if len(beyond) else 0.0
    return record


def prescribed_footprint(msh: Path, delta: float, youngs_modulus: float, poisson_ratio: float,
                         w: float, sx: float, sy: float) -> dict:
    """The sharp rigid punch without a contact solver (module doc): force of the block whose top nodes
    strictly inside the footprint are moved down by delta, free sideways, its base clamped."""
    from dolfinx_reference import Body, ReferenceModel

    start = time.perf_counter()
    block = read_body(msh, "block", ["block_contact", "block_base"])
    model = ReferenceModel(msh, {"block": block.x})
    K = model.stiffness(Body("block", youngs_modulus, poisson_ratio))
    n = block.num_nodes
    g = np.full(3 * n, np.nan)
    base = np.unique(block.facets["block_base"])
    top = np.unique(block.facets["block_contact"])
    for c in range(3):
        g[3 * base + c] = 0.0
    x = block.x[top]
    inside = top[(np.abs(x[:, 0] - sx) < w - 1e-9) & (np.abs(x[:, 1] - sy) < w - 1e-9)]
    g[3 * inside + 2] = -delta
    u = solve_constrained(K, np.zeros(3 * n), g, f"{msh}: prescribed footprint")
    r = (K @ u).reshape(-1, 3)
    return {"force": float(-r[inside, 2].sum()), "footprint_nodes": int(len(inside)),
            "seconds": time.perf_counter() - start}


def plane_solve(msh: Path, dim: int, body: str, delta: float, youngs_modulus: float,
                poisson_ratio: float) -> dict:
    """``body`` of ``msh`` (groups ``<body>_contact``, ``<body>_top``) pressed by ``delta`` onto the
    rigid plane x_v = 0 (module doc)."""
    start = time.perf_counter()
    mesh = read_body(msh, body, [f"{body}_contact", f"{body}_top"])
    model = RigidFlatContact(mesh, f"{body}_contact", f"{body}_top", youngs_modulus, poisson_ratio)
    model.normals = None
    solution, bounded, contact, reaction = _solve(model, delta)
    return _record(model, solution, bounded, contact, reaction, delta, start, turned=False)


def _pressed_pair(msh: Path, moving: str, delta: float, youngs_modulus: float, poisson_ratio: float,
                  block_modulus: float | None) -> tuple:
    """The two elastic bodies of a two-body reference without contact: ``moving`` (groups
    ``<moving>_contact``, ``<moving>_top``) and the block (``block_contact``, ``block_base``), both
    stiffness matrices of dolfinx in one block-diagonal matrix (``moving``'s unknowns first), the
    moving body's top moved down by ``delta`` with its lateral components held, the block's base
    clamped. Returns (moving body, block, K, the top's nodes, the free unknowns, the displacement of
    the prescribed motion alone u0, the sparse LU of K on the free unknowns, the moving body's
    contact nodes off its top and their heights above the block's top, which must be a plane
    x_v = 0 with none of them below it)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spl

    from dolfinx_reference import Body, ReferenceModel

    body = read_body(msh, moving, [f"{moving}_contact", f"{moving}_top"])
    block = read_body(msh, "block", ["block_contact", "block_base"])
    model = ReferenceModel(msh, {moving: body.x, "block": block.x})
    K = sp.block_diag([model.stiffness(Body(moving, youngs_modulus, poisson_ratio)),
                       model.stiffness(Body("block", block_modulus or youngs_modulus, poisson_ratio))]).tocsr()
    dim = model.dim
    fixed = np.full(K.shape[0], np.nan)
    top = np.unique(body.facets[f"{moving}_top"])
    base = np.unique(block.facets["block_base"])
    for k in range(dim):
        fixed[dim * top + k] = -delta if k == dim - 1 else 0.0
        fixed[dim * body.num_nodes + dim * base + k] = 0.0
    free = np.flatnonzero(np.isnan(fixed))
    u0 = np.where(np.isnan(fixed), 0.0, fixed)
    factor = spl.splu(K[free][:, free].tocsc())
    u0[free] = factor.solve(-(K @ u0)[free])
    if np.abs(block.x[np.unique(block.facets["block_contact"]), dim - 1]).max() > 1e-12:
        raise ReferenceFailure(f"{msh}: the block's top is not at x_{dim - 1} = 0")
    nodes = np.setdiff1d(np.unique(body.facets[f"{moving}_contact"]), top)
    height = body.x[nodes, dim - 1]
    if (height < -1e-12).any():
        raise ReferenceFailure(f"{msh}: {moving} contact nodes below the block's top (overlap)")
    return body, block, K, top, free, u0, factor, nodes, height


def two_body_solve(msh: Path, delta: float, youngs_modulus: float, poisson_ratio: float,
                   reach: float = 2.0, max_iterations: int = 400,
                   block_modulus: float | None = None, update: str = "exact",
                   start_from: dict | None = None) -> dict:
    """The square of ``geo/tilted_square_2d.geo`` pressed by ``delta`` into the block of the same
    material, both elastic (module doc, ``two_body_solve``).

    Both stiffness matrices are dolfinx's (``dolfinx_reference.ReferenceModel``, plane strain); the
    contact is node to segment from the square's contact nodes onto the block's top, the gap
    measured on the deformed P1 surfaces as internodes measures it (``docs/method.md`` 3.1: the
    distance to the plane of the facet of the closest point, along that facet's outward normal),
    each Newton step's constraints linearized there: g_i + m . (du_i - sum_k b_k du_k) >= 0. The
    multipliers of one step solve the linear complementarity problem W lambda + q >= 0,
    lambda >= 0, complementary (W = B K^-1 B^T, SPD), exactly, as the bound-constrained
    least-squares problem min |L^T lambda + L^-1 q|, lambda >= 0 (W = L L^T, NNLS: a finite
    active-set method). Where the closest facet meets a neighbour at a concave vertex (the bottom
    of the crater the corner digs), the node gets a row for the neighbour's plane too: the block's
    outside is there the intersection of the two half-planes, and the force on a node at the
    vertex lies anywhere in the cone of the two normals. With one row only, the node's force is
    along one wall's normal, its next iterate on the other wall, and the iteration swings with
    period two (the corner 0.8 to 3.5 spacings sideways, the force 0.876 to 0.956 at h 0.001 and a
    2% approach), as internodes's loop does. Steps until no displacement changes by more than
    1e-6 delta (the force then known to about 1e-5; where rows switch between the walls the
    convergence is linear: about 300 steps at h 0.001, block spacing 0.7 h, a 4% approach). The first step, paired in the reference configuration (small sliding), is
    ``force_small_sliding``.

    ``update="primal-dual"``: a second path to the same discrete problem, the one internodes's loop
    takes: each linearization takes one primal-dual active-set update (rows active where their
    gap is negative or their multiplier was positive at the last step, solved as equalities), the set
    carried from step to step by (node, facet). Where both paths stop on an answer whose KKT
    conditions hold, the two are solutions of the same discrete problem; where they differ, that
    problem has more than one (the gap measured on the deformed surfaces is not convex in the
    displacements), and no solver of it can be held to closer than their difference.

    ``start_from``: the displacement to start from, ``{gmsh node tag: (u_x, u_y)}`` for every node of
    both bodies (an answer of internodes), each step linearized where the last one ended from the
    first on (no small-sliding step): the solution of this discrete problem nearest that answer,
    where the problem has several (the gap measured on the deformed surfaces is not convex in the
    displacements). Where the answer is near one of them, the steps end there; internodes carries
    the square's force to the block by its interface operators, this reference node to segment,
    so the two differ by that discretization's share.

    ``block_modulus``: the block's (default: the square's; a rigid block's check, module doc).
    Candidates: the square's contact nodes within ``reach`` delta of the block in the reference
    configuration (``uncovered_penetration``: the deepest other square contact node below the
    deformed block's top at the answer, over the square's spacing; must be 0).
    """
    start = time.perf_counter()
    square, block, K, top, free, u0, factor, nodes, y = _pressed_pair(msh, "square", delta, youngs_modulus,
                                                                      poisson_ratio, block_modulus)
    ns = square.num_nodes
    size = K.shape[0]
    candidates = nodes[y <= reach * delta]
    h = float(np.median(np.linalg.norm(np.diff(square.x[candidates[np.argsort(square.x[candidates, 0])], :2],
                                                axis=0), axis=1)))
    segments = block.facets["block_contact"]  # block-local nodes
    both = np.concatenate([segments[:, 0], segments[:, 1]])

    def position(u):
        xs = square.x[:, :2] + u[: 2 * ns].reshape(-1, 2)
        xb = block.x[:, :2] + u[2 * ns:].reshape(-1, 2)
        return xs, xb

    def normal(xb, f):
        a, b = xb[segments[f, 0]], xb[segments[f, 1]]
        m = np.array([a[1] - b[1], b[0] - a[0]]) / np.linalg.norm(b - a)
        return m if m[1] > 0 else -m  # the block's top faces up

    def constraints(u):
        xs, xb = position(u)
        a, b = xb[segments[:, 0]], xb[segments[:, 1]]
        rows, gaps, owners, walls = [], [], [], []
        for node in candidates:
            p = xs[node]
            t = np.clip(np.einsum("ij,ij->i", p - a, b - a) / np.einsum("ij,ij->i", b - a, b - a), 0, 1)
            closest = a + t[:, None] * (b - a)
            f = int(np.argmin(np.linalg.norm(p - closest, axis=1)))
            facets = [f]
            for vertex in segments[f]:
                for g in np.flatnonzero((segments == vertex).any(axis=1)):
                    other = segments[g][segments[g] != vertex][0]
                    if g != f and normal(xb, f) @ (xb[other] - xb[vertex]) > 0:  # concave vertex
                        facets.append(int(g))
            for g in facets:
                m = normal(xb, g)
                row = np.zeros(size)
                row[2 * node: 2 * node + 2] = m
                row[2 * ns + 2 * segments[g, 0]: 2 * ns + 2 * segments[g, 0] + 2] -= (1 - t[g]) * m
                row[2 * ns + 2 * segments[g, 1]: 2 * ns + 2 * segments[g, 1] + 2] -= t[g] * m
                rows.append(row)
                gaps.append(float(m @ (p - closest[g])))
                owners.append(int(node))
                walls.append((int(node), int(g)))
        return np.array(rows), np.array(gaps), np.array(owners), walls

    if update not in ("exact", "primal-dual"):
        raise ValueError(f"update: 'exact' or 'primal-dual', not {update!r}")
    u = u0.copy()
    if start_from is not None:
        tags = np.concatenate([square.node_tags, block.node_tags]).astype(int)
        given = np.array([start_from[int(t)] for t in tags], dtype=float).reshape(-1)
        u = u0.copy()
        u[free] = given[free]
    held = set()  # primal-dual: the (node, facet) rows whose multiplier was positive
    small_sliding = None
    change = math.inf
    for iteration in range(1, max_iterations + 1):
        small_step = iteration == 1 and start_from is None
        if small_step:  # small sliding: every candidate on the block's top under it, along y
            rows = np.zeros((len(candidates), size))
            for r, node in enumerate(candidates):
                x = square.x[node, 0]
                xb = block.x[segments, 0]
                f = int(np.flatnonzero((xb.min(axis=1) <= x) & (x <= xb.max(axis=1)))[0])
                t = (x - block.x[segments[f, 0], 0]) / (block.x[segments[f, 1], 0] - block.x[segments[f, 0], 0])
                rows[r, 2 * node + 1] = 1.0
                rows[r, 2 * ns + 2 * segments[f, 0] + 1] -= 1.0 - t
                rows[r, 2 * ns + 2 * segments[f, 1] + 1] -= t
            gaps, owners = square.x[candidates, 1].copy(), candidates
            walls = [(int(node), -1) for node in candidates]
        else:
            rows, gaps, owners, walls = constraints(u)
        solved = np.zeros_like(rows)
        for r in range(len(rows)):
            solved[r, free] = factor.solve(rows[r, free])
        W = rows[:, free] @ solved[:, free].T
        W = 0.5 * (W + W.T)
        at = np.zeros(size) if small_step else u  # the linearization point
        q = gaps + rows @ (u0 - at)
        lam = _step_multipliers(W, q, update, small_step, walls, gaps, held)
        held = {wall for wall, value in zip(walls, lam) if value > 0.0}
        new = u0 + solved.T @ lam
        change = float(np.abs(new - u).max())
        u = new
        if small_step:
            small_sliding = float(lam.sum())
        if iteration > 1 and change <= 1e-6 * delta:
            break
    rows, gaps, owners, _ = constraints(u)
    # the last step's multipliers belong to the last linearization (equal at convergence)
    linear = q + W @ lam
    reaction = K @ u
    top_force = float(-reaction[2 * top + 1].sum())
    contact_nodes = np.unique(owners[np.flatnonzero(gaps <= 1e-9 * delta)])
    xs, xb = position(u)
    order = np.unique(both)
    order = order[np.argsort(xb[order, 0])]
    uncovered = max([0.0] + [float(np.interp(xs[n, 0], xb[order, 0], xb[order, 1]) - xs[n, 1])
                             for n in np.setdiff1d(nodes, candidates)])
    corner = int(nodes[np.argmin(y)])
    kkt = _kkt(gaps, lam, linear, change, delta)
    return {
        "delta": delta, "num_nodes": int(ns + block.num_nodes), "force": top_force,
        "force_small_sliding": small_sliding,
        "nodes_constrained": int(len(candidates)), "nodes_in_contact": int(len(contact_nodes)),
        "contact_tags": square.node_tags[contact_nodes].astype(int).tolist(),
        "contact_deformed": np.pad(xs[contact_nodes], ((0, 0), (0, 1))).tolist(),
        "corner_slide_over_h": float((xs[corner, 0] - square.x[corner, 0]) / h),
        "uncovered_penetration": float(uncovered / h),
        "snes": {"iterations": iteration, "converged_reason": 1 if kkt["passed"] else -1},
        "kkt": kkt, "seconds": time.perf_counter() - start,
    }


def _step_multipliers(W: np.ndarray, q: np.ndarray, update: str, first: bool, walls: list, gaps: np.ndarray,
                      held: set) -> np.ndarray:
    """The multipliers of one linearization of ``two_body_solve`` / ``two_body_solve_3d``: the linear
    complementarity problem W lambda + q >= 0, lambda >= 0, complementary, solved exactly as the
    bound-constrained least-squares problem min |L^T lambda + L^-1 q|, lambda >= 0 (W = L L^T, NNLS)
    where ``update`` is "exact" or at the first step; else one primal-dual active-set update: the rows
    whose (node, facet) ``walls`` entry was ``held`` (a positive multiplier at the last step; (node, -1)
    a node the first step, one row a node, held) or whose gap is negative, solved as equalities."""
    import scipy.linalg
    from scipy.optimize import nnls

    if update == "exact" or first:
        L = np.linalg.cholesky(W + 1e-13 * np.trace(W) / len(W) * np.eye(len(W)))
        lam, _ = nnls(L.T, -scipy.linalg.solve_triangular(L, q, lower=True), maxiter=50 * len(q))
        return lam
    active = np.array([wall in held or (wall[0], -1) in held or gap < 0.0 for wall, gap in zip(walls, gaps)])
    lam = np.zeros(len(q))
    lam[active] = np.linalg.solve(W[np.ix_(active, active)], -q[active])
    return lam


def _kkt(gaps: np.ndarray, lam: np.ndarray, linear: np.ndarray, change: float, delta: float) -> dict:
    """The KKT figures of a two-body answer (the gaps at the answer, the last linearization's
    multipliers and linearized gaps, the last step's largest change of a displacement) and whether
    they hold."""
    kkt = {"penetration": float(max(0.0, -gaps.min()) / delta),
           "tension": float(max(0.0, -lam.min()) / max(lam.max(), 1e-300)),
           "complementarity": float(np.abs(lam * linear).max() / (max(lam.max(), 1e-300) * delta)),
           "change": change / delta}
    kkt["passed"] = bool(kkt["penetration"] <= 1e-8 and kkt["tension"] <= 1e-8
                         and kkt["complementarity"] <= 1e-8 and kkt["change"] <= 1e-6)
    return kkt


def _closest_on_triangles(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple:
    """The closest points to ``p`` (3,) of the triangles (a, b, c) (each (m, 3)) and their barycentric
    coordinates (m, 3): the projection onto the triangle's plane where it falls inside, else the
    closest point of the nearest of its three edges."""
    ab, ac = b - a, c - a
    n = np.cross(ab, ac)
    nn = np.einsum("ij,ij->i", n, n)
    w = p - a
    beta = np.einsum("ij,ij->i", np.cross(w, ac), n) / nn
    gamma = np.einsum("ij,ij->i", np.cross(ab, w), n) / nn
    weights = np.stack([1 - beta - gamma, beta, gamma], axis=1)
    inside = (weights >= 0).all(axis=1)
    best = np.full(len(a), np.inf)
    edge_weights = np.zeros_like(weights)
    for k, (s, e) in enumerate(((a, b), (b, c), (c, a))):
        se = e - s
        t = np.clip(np.einsum("ij,ij->i", p - s, se) / np.einsum("ij,ij->i", se, se), 0.0, 1.0)
        d = np.linalg.norm(s + t[:, None] * se - p, axis=1)
        closer = d < best
        best[closer] = d[closer]
        ew = np.zeros_like(weights)
        ew[:, k], ew[:, (k + 1) % 3] = 1 - t, t
        edge_weights[closer] = ew[closer]
    weights = np.where(inside[:, None], weights, edge_weights)
    points = weights[:, :1] * a + weights[:, 1:2] * b + weights[:, 2:] * c
    return points, weights


def two_body_solve_3d(msh: Path, delta: float, youngs_modulus: float, poisson_ratio: float,
                      reach: float = 2.0, max_iterations: int = 400,
                      block_modulus: float | None = None, update: str = "exact") -> dict:
    """The cube of ``geo/tilted_cube_3d.geo`` pressed by ``delta`` (its top faces moved down, lateral
    components held) into the block of the same material (its base clamped), both elastic: the 3D
    sibling of ``two_body_solve``, node to triangle.

    The same method: dolfinx's stiffness matrices; the cube's contact nodes within ``reach`` delta of
    the block's top (the candidates) held against the block's deformed P1 top, each candidate's gap
    the distance to the plane of the facet of its closest point along that facet's outward normal,
    linearized there, g + m . (du - sum_k b_k du_k) >= 0 (b the closest point's barycentric
    coordinates); where a facet that shares a vertex with the closest one lies wholly above its plane
    (a concave edge or vertex: the bottom of the groove the edge digs), a row for that facet's plane
    too. Each linearization's complementarity problem is solved exactly (NNLS, ``update="exact"``) or
    by one primal-dual update (``update="primal-dual"``), until no displacement changes by more than
    1e-6 delta and no candidate is inside its facets by more than 1e-8 delta; the first step is paired in the reference configuration (small sliding,
    ``force_small_sliding``). The operator W = B K^-1 B^T is formed from the compliance of the
    unknowns the rows can reach (the candidates and the block's top nodes within a few spacings of
    them, one multi-right-hand-side solve), so a step costs no solve; the displacement of the other
    unknowns is solved once, at the answer. ``uncovered_penetration``: the deepest cube contact
    node outside the candidates below the deformed block's top (its closest facet's plane), over the
    cube's spacing; must be 0.
    """
    import scipy.sparse as sp
    from scipy.spatial import cKDTree

    start = time.perf_counter()
    cube, block, K, top, free, u0, factor, nodes, z = _pressed_pair(msh, "cube", delta, youngs_modulus,
                                                                    poisson_ratio, block_modulus)
    nc = cube.num_nodes
    size = K.shape[0]
    triangles = block.facets["block_contact"]  # block-local nodes, (m, 3)
    candidates = nodes[z <= reach * delta]
    faces = cube.facets["cube_contact"]
    near_faces = faces[np.isin(faces, candidates).all(axis=1)]
    h = float(np.median(np.linalg.norm(cube.x[near_faces] - cube.x[np.roll(near_faces, 1, axis=1)], axis=2)))
    # the block's top facets the rows may reach: within a few of their own diameters of a candidate
    centroids = block.x[triangles].mean(axis=1)
    diameter = np.linalg.norm(block.x[triangles] - block.x[np.roll(triangles, 1, axis=1)], axis=2).max(axis=1)
    lateral = cKDTree(cube.x[candidates, :2]).query(centroids[:, :2])[0]
    reachable = np.flatnonzero(lateral <= 4.0 * diameter + reach * delta)
    near = np.unique(triangles[reachable])
    # the unknowns the rows reach: the candidates' and the reachable facets' nodes (all free)
    reached = np.concatenate([3 * np.repeat(candidates, 3) + np.tile(np.arange(3), len(candidates)),
                              3 * nc + 3 * np.repeat(near, 3) + np.tile(np.arange(3), len(near))])
    position_in_free = np.full(size, -1)
    position_in_free[free] = np.arange(len(free))
    if (position_in_free[reached] < 0).any():
        raise ReferenceFailure(f"{msh}: a contact unknown is prescribed")
    unit = sp.csc_matrix((np.ones(len(reached)), (position_in_free[reached], np.arange(len(reached)))),
                         shape=(len(free), len(reached)))
    compliance = factor.solve(unit.toarray())[position_in_free[reached]]  # K^-1 on the reached unknowns
    column = np.full(size, -1)
    column[reached] = np.arange(len(reached))
    # every pair (f, g) of reachable facets that share a vertex, with g's vertices not on f (-1: none)
    by_vertex: dict = {}
    for f in reachable:
        for vertex in triangles[f]:
            by_vertex.setdefault(int(vertex), []).append(int(f))
    pairs = sorted({(f, g) for around in by_vertex.values() for f in around for g in around if f != g})
    pair_f = np.array([f for f, _ in pairs])
    pair_g = np.array([g for _, g in pairs])
    off_f = [[v for v in triangles[g] if v not in triangles[f]] for f, g in pairs]
    pair_others = np.array([vertices + [-1] * (2 - len(vertices)) for vertices in off_f])

    def positions(u):
        return cube.x + u[: 3 * nc].reshape(-1, 3), block.x + u[3 * nc:].reshape(-1, 3)

    def facet_normals(xb):
        a, b, c = xb[triangles].transpose(1, 0, 2)
        m = np.cross(b - a, c - a)
        m /= np.linalg.norm(m, axis=1)[:, None]
        return m * np.sign(m[:, 2])[:, None]  # the block's top faces up

    def rows_matrix(nodes, facets, weights, normals):
        """The linearized gap rows m . (du_node - sum_k w_k du_k) as a sparse matrix over the reached
        unknowns, one row per (node, facet)."""
        k = np.arange(3)
        node_columns = column[3 * nodes[:, None] + k]  # (r, 3)
        vertex_columns = column[3 * nc + 3 * triangles[facets][:, :, None] + k]  # (r, 3 vertices, 3)
        values = np.concatenate([normals, -(weights[:, :, None] * normals[:, None, :]).reshape(-1, 9)], axis=1)
        columns = np.concatenate([node_columns, vertex_columns.reshape(-1, 9)], axis=1)
        r = np.repeat(np.arange(len(nodes)), 12)
        assert (columns >= 0).all(), "a row reaches an unknown outside the compliance"
        return sp.csr_matrix((values.ravel(), (r, columns.ravel())), shape=(len(nodes), len(reached)))

    def closest_facets(xb, points, among):
        """(facet, closest point, its barycentric coordinates) of each of ``points`` over the facets
        ``among`` (indices into ``triangles``): a facet nearer than the nearest centroid has its
        centroid within one diameter more. Ties go to the facet the search lists first."""
        tree = cKDTree(xb[triangles[among]].mean(axis=1))
        nearest = tree.query(points)[0]
        lists = tree.query_ball_point(points, nearest + 1.01 * diameter[among].max())
        point = np.repeat(np.arange(len(points)), [len(around) for around in lists])
        facet = among[np.concatenate([np.array(around, dtype=int) for around in lists])]
        q, w = _closest_on_triangles(points[point], *xb[triangles[facet]].transpose(1, 0, 2))
        distance = np.linalg.norm(q - points[point], axis=1)
        order = np.lexsort((distance, point))
        best = order[np.searchsorted(point[order], np.arange(len(points)))]
        return facet[best], q[best], w[best]

    def constraints(u):
        """The rows, gaps, their nodes and (node, facet) walls at the displacement u: each candidate's
        closest facet, then the facets around it wholly above its plane (concave), node by node."""
        xs, xb = positions(u)
        normals = facet_normals(xb)
        points = xs[candidates]
        f, q, w = closest_facets(xb, points, reachable)
        first, last = np.searchsorted(pair_f, f, "left"), np.searchsorted(pair_f, f, "right")
        owner = np.repeat(np.arange(len(candidates)), last - first)
        pair = np.concatenate([np.arange(a, b) for a, b in zip(first, last)]).astype(int)
        others = pair_others[pair]
        height = np.einsum("ijk,ik->ij", xb[others] - xb[triangles[f[owner], 0]][:, None, :], normals[f[owner]])
        concave = ((height > 0) | (others < 0)).all(axis=1)
        owner, g = owner[concave], pair_g[pair[concave]]
        qg, wg = _closest_on_triangles(points[owner], *xb[triangles[g]].transpose(1, 0, 2))
        # the closest facet's row first, then the concave ones, node by node
        which = np.concatenate([np.arange(len(candidates)), owner])
        order = np.argsort(which, kind="stable")
        facets = np.concatenate([f, g])[order]
        closest = np.concatenate([q, qg])[order]
        weights = np.concatenate([w, wg])[order]
        nodes = candidates[which[order]]
        m = normals[facets]
        gaps = np.einsum("ij,ij->i", m, xs[nodes] - closest)
        walls = list(zip(nodes.tolist(), facets.tolist()))
        return rows_matrix(nodes, facets, weights, m), gaps, nodes, walls

    if update not in ("exact", "primal-dual"):
        raise ValueError(f"update: 'exact' or 'primal-dual', not {update!r}")
    u = u0.copy()
    held: set = set()
    # the first step is paired in the reference configuration (small sliding): every candidate on
    # the block's top under it, along z
    under, _, weights = closest_facets(block.x, np.pad(cube.x[candidates, :2], ((0, 0), (0, 1))), reachable)
    B = rows_matrix(candidates, under, weights, np.tile([0.0, 0.0, 1.0], (len(candidates), 1)))
    gaps = cube.x[candidates, 2].copy()
    walls = [(int(node), -1) for node in candidates]
    changes = []
    for iteration in range(1, max_iterations + 1):
        BC = np.asarray(B @ compliance)
        W = np.asarray((B @ BC.T).T)
        W = 0.5 * (W + W.T)
        at = np.zeros(size) if iteration == 1 else u  # the linearization point
        q = gaps + B @ (u0 - at)[reached]
        lam = _step_multipliers(W, q, update, iteration == 1, walls, gaps, held)
        held = {wall for wall, value in zip(walls, lam) if value > 0.0}
        new = u0.copy()
        new[reached] += BC.T @ lam
        change = float(np.abs(new[reached] - u[reached]).max())
        changes.append(change / delta)
        u = new
        if iteration == 1:
            small_sliding = float(lam.sum())
        next_rows, next_gaps, _, next_walls = constraints(u)
        # a step that changes nothing may still leave a node a little inside a facet it switched to
        if iteration > 1 and change <= 1e-6 * delta and next_gaps.min() >= -1e-8 * delta:
            break
        if iteration < max_iterations:  # the last step's rows stay with its multipliers
            B, gaps, walls = next_rows, next_gaps, next_walls
    linear = q + W @ lam
    # the whole displacement at the answer: u0 + K^-1 B^T lambda
    load = np.zeros(size)
    load[reached] = B.T @ lam
    u = u0.copy()
    u[free] += factor.solve(load[free])
    _, gaps, owners, _ = constraints(u)
    reaction = K @ u
    top_force = float(-reaction[3 * top + 2].sum())
    contact_nodes = np.unique(owners[np.flatnonzero(gaps <= 1e-9 * delta)])
    xs, xb = positions(u)
    everywhere = np.arange(len(triangles))
    if not np.isin(closest_facets(xb, xs[candidates], everywhere)[0], reachable).all():
        raise ReferenceFailure(f"{msh}: a candidate's closest facet lies beyond the facets the rows reach")
    beyond = np.setdiff1d(nodes, candidates)
    uncovered = 0.0
    if len(beyond):
        f, q, _ = closest_facets(xb, xs[beyond], everywhere)
        uncovered = max(0.0, -float(np.einsum("ij,ij->i", facet_normals(xb)[f], xs[beyond] - q).min()))
    kkt = _kkt(gaps, lam, linear, change, delta)
    edge = nodes[z <= z.min() + 1e-9]
    slide = np.linalg.norm((xs[edge] - cube.x[edge])[:, :2], axis=1).max()
    return {
        "delta": delta, "num_nodes": int(nc + block.num_nodes), "force": top_force,
        "force_small_sliding": small_sliding,
        "nodes_constrained": int(len(candidates)), "nodes_in_contact": int(len(contact_nodes)),
        "contact_tags": cube.node_tags[contact_nodes].astype(int).tolist(),
        "contact_deformed": xs[contact_nodes].tolist(),
        "corner_slide_over_h": float(slide / h),
        "uncovered_penetration": float(uncovered / h),
        "snes": {"iterations": iteration, "converged_reason": 1 if kkt["passed"] else -1},
        "kkt": kkt, "changes": changes, "seconds": time.perf_counter() - start,
    }


def converged(reference: dict) -> bool:
    """The VI converged and its KKT conditions hold."""
    return bool(reference["snes"]["converged_reason"] > 0 and reference["kkt"].get("passed"))


def verify(folder: Path) -> dict:
    """The references checked independently (``edge_reference.py verify``; the figures are quoted in
    validation/README.md): meshes in ``folder``."""
    import flat_reference
    from suite import mesh_geo

    E, nu = 1000.0, 0.3
    w, sx, sy = 0.3, 0.0137, 0.0071
    results: dict = {}

    def msh(script, dim, parameters):
        name = script + "".join(f"_{k}{v:g}" for k, v in parameters.items()) + ".msh"
        return mesh_geo(script, dim, parameters, folder / name)

    # 1. The sharp punch: the VI against the footprint prescribed in one linear solve.
    delta = 0.0025
    sharp = msh("square_punch_3d", 3, {"h_b": 0.05, "h_p": 0.07, "rho": 0.0})
    vi = punch_solve(sharp, delta, E, nu, footprint={"w": w, "sx": sx, "sy": sy})
    linear = prescribed_footprint(sharp, delta, E, nu, w, sx, sy)
    results["sharp: VI against prescribed footprint"] = {
        "vi": vi["force"], "prescribed": linear["force"], "relative": vi["force"] / linear["force"] - 1}
    # 2. The exact-fillet obstacle with a vanishing radius on the sharp mesh is the sharp punch.
    tiny = punch_solve(sharp, delta, E, nu, exact={"w": w, "rho": 1e-7, "sx": sx, "sy": sy})
    results["fillet obstacle, rho -> 0, against the sharp punch"] = {
        "fillet": tiny["force"], "sharp": vi["force"], "relative": tiny["force"] / vi["force"] - 1}
    # 3. The fillet: the analytic surface is the meshed one; exact against the punch's P1 face.
    filleted = msh("square_punch_3d", 3, {"h_b": 0.05, "h_p": 0.07, "rho": 0.1})
    for d in (0.0025, 0.01):
        exact = punch_solve(filleted, d, E, nu, exact={"w": w, "rho": 0.1, "sx": sx, "sy": sy})
        p1 = punch_solve(filleted, d, E, nu)
        results[f"fillet d={d:g}: exact against the P1 face"] = {
            "exact": exact["force"], "p1_face": p1["force"], "relative": p1["force"] / exact["force"] - 1,
            "contact_beyond_flat": exact["contact_beyond_flat"]}
    results["fillet surface error / rho"] = fillet_surface_error(filleted, w, 0.1, sx, sy)
    # 4. The sharp punch under refinement, and on a block large enough to compare with the rigid
    # square punch on a half-space: P = 2 beta E* sqrt(A / pi) delta, beta = 1.012 (square).
    estar = E / (1 - nu**2)
    half_space = 2 * 1.012 * estar * math.sqrt((2 * w) ** 2 / math.pi) * delta
    for label, extra, spacings in (
            ("block 2 x 2 x 1", {}, (0.05, 0.035, 0.025)),
            ("block 8 x 8 x 4", {"W": 4.0, "H": 4.0, "h_far": 0.5, "d_c": 0.45}, (0.07, 0.05, 0.035)),
            ("block 16 x 16 x 8", {"W": 8.0, "H": 8.0, "h_far": 0.5, "d_c": 0.45}, (0.05,))):
        forces = {}
        for h in spacings:
            m = msh("square_punch_3d", 3, {"h_b": h, "h_p": 0.07, "rho": 0.0, **extra})
            forces[h] = prescribed_footprint(m, delta, E, nu, w, sx, sy)["force"]
        results[f"sharp punch refined, {label}"] = {"forces": forces, "half_space_estimate": half_space}
    # 5. The rigid plane: an untilted block face down (the upper block of flat_blocks) on the plane
    # against dolfinx's union of two such blocks clamped at their ends (flat_reference.union_solve:
    # the interface is a symmetry plane, so the union at 2 d is each half on a frictionless plane at d).
    for dim, b in ((3, {"W_l": 0.5, "H_l": 0.5, "H_u": 0.5}), (2, {"W_l": 1.0, "H_l": 0.5, "H_u": 0.5})):
        h = 0.05 if dim == 3 else 0.025
        d = 0.005
        two = msh(f"flat_blocks_{dim}d", dim, {**b, "W_u": b["W_l"], "h_l": h, "h_u": h})
        union = msh(f"flat_blocks_{dim}d", dim, {"union": 1, **b, "h_l": h, "h_u": h})
        plane = plane_solve(two, dim, "upper", d, E, nu)
        whole = flat_reference.union_solve(union, dim, "clamped", 2 * d, E, nu, b["W_l"], b["H_l"], b["H_u"])
        results[f"plane {dim}D: upper block on the plane against the union"] = {
            "plane": plane["force"], "union": whole["force"], "relative": plane["force"] / whole["force"] - 1,
            "in_contact": plane["nodes_in_contact"], "candidates": plane["nodes_constrained"]}
    # 6. The two-body references with the block made rigid: the plane references of the same meshes.
    for dim, script, body, parameters, d in ((2, "tilted_square_2d", "square", {"h_c": 0.001, "h_b": 0.0014}, 0.008),
                                             (3, "tilted_cube_3d", "cube", {"h_c": 0.01, "h_b": 0.014}, 0.004)):
        m = msh(script, dim, parameters)
        two = (two_body_solve if dim == 2 else two_body_solve_3d)(m, d, E, nu, block_modulus=1e12)
        plane = plane_solve(m, dim, body, d, E, nu)
        results[f"two bodies {dim}D, the block rigid, against the plane"] = {
            "two_bodies": two["force"], "plane": plane["force"], "relative": two["force"] / plane["force"] - 1,
            "two_bodies_converged": converged(two), "in_contact": [two["nodes_in_contact"], plane["nodes_in_contact"]]}
    return results


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    punch = sub.add_parser("punch", help="the block of a square_punch_3d mesh under the punch taken as rigid")
    punch.add_argument("mesh", type=Path)
    punch.add_argument("--delta", type=float, required=True)
    punch.add_argument("--rho", type=float, default=0.0, help="> 0: the exact fillet (with --w, --sx, --sy)")
    punch.add_argument("--w", type=float, default=0.3)
    punch.add_argument("--sx", type=float, default=0.0137)
    punch.add_argument("--sy", type=float, default=0.0071)
    check = sub.add_parser("verify", help="the independent checks of the references (validation/README.md)")
    check.add_argument("--folder", type=Path, default=Path(__file__).resolve().parent / "build" / "edge_sweep"
                       / "verify")
    plane = sub.add_parser("plane", help="a body pressed onto the rigid plane x_v = 0")
    plane.add_argument("mesh", type=Path)
    plane.add_argument("--delta", type=float, required=True)
    plane.add_argument("--body", required=True)
    plane.add_argument("--dim", type=int, default=3)
    for p in (punch, plane, check):
        p.add_argument("--E", type=float, default=1000.0)
        p.add_argument("--nu", type=float, default=0.3)
    args = parser.parse_args(argv)
    if args.command == "verify":
        print(json.dumps(verify(args.folder), indent=1))
        return 0
    if args.command == "punch":
        exact = {"w": args.w, "rho": args.rho, "sx": args.sx, "sy": args.sy} if args.rho > 0 else None
        data = punch_solve(args.mesh, args.delta, args.E, args.nu, exact,
                           footprint={"w": args.w, "sx": args.sx, "sy": args.sy})
    else:
        data = plane_solve(args.mesh, args.dim, args.body, args.delta, args.E, args.nu)
    data.pop("contact_deformed")
    data.pop("contact_tags")
    print(json.dumps(data, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
