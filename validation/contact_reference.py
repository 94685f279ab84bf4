#!/usr/bin/python3
"""Independent dolfinx reference for frictionless contact with a rigid flat.

Problem. One elastic body of a two-body contact mesh -- the hemisphere of
``geo/hemisphere_on_block.geo`` (3D) or the half-disc of
``geo/half_disc_on_block.geo`` (2D, plane strain) -- is pressed onto the
rigid plane x_v = 0 (v the vertical axis: z in 3D, y in 2D; the plane is the
block's top face). Small-strain isotropic linear elasticity, P1 elements,

    a(u, w) = int_body sigma(u) : eps(w) dx,   sigma = 2 mu eps + lambda tr(eps) I,

the top face ("sphere_top" / "disc_top") displaced by (0, 0, -delta) /
(0, -delta), and frictionless node-to-plane contact at the nodes of the
candidate surface ("sphere_contact" / "disc_contact"):

    g_i = x_i,v + u_i,v >= 0,   r_i,v >= 0,   g_i r_i,v = 0,   r_i,lateral = 0,

with r = K u the nodal reaction (the residual of the elastic form, no other
load). This is the discrete problem: minimise 1/2 u.K u over the displacements
with the Dirichlet data and the bounds u_i,v >= -x_i,v. The rigid flat stands
for the block of the INTERNODES run made 1e4 times stiffer than the body.

Method (owes nothing to internodes). The mesh of the body alone -- exactly
the gmsh nodes and tetrahedra / triangles of its physical group, which is
what internodes reads for that body -- is passed to
``dolfinx.mesh.create_mesh``; K is assembled by dolfinx/UFL, and the bound
constrained problem is solved by PETSc's reduced-space semismooth Newton
method for variational inequalities (SNES ``vinewtonrsls``,
``setVariableBounds``), with a direct (MUMPS LU) inner solve.

Why the VI solver and not a penalty: it imposes the node-to-plane
constraint exactly, so its solution *is* the discrete contact solution, with
no parameter to drive to a limit; on this linear problem the active-set
Newton iteration terminates in a few steps once the contact set is found.
Its convergence is certified twice, independently of PETSc's own
convergence test: (1) the KKT conditions above are checked on the returned
solution (stationarity on the free dofs, feasibility, non-negative
reactions, complementarity), and (2) a nodal penalty formulation
(semismooth Newton, ``newtonls``; factors ``--kappas``, 1e1 to 1e5 by
default) is solved for growing penalty stiffness, and its force is shown to
converge to the VI force, the difference falling like 1/kappa.

Post-processing (definitions used for both codes by ``rigid_flat_comparison.py``):

* contact force P = sum over the contact-surface nodes of r_i,v (checked
  against minus the vertical reaction of the top face; P is per unit
  thickness in 2D);
* nodal pressure p_i = r_i,v / A_i, A_i = sum_j M_ij the lumped area
  (length in 2D) of node i, M the P1 surface mass matrix of the
  candidate-surface facets (areas of the curved surface, not of its
  projection on the plane: they differ by 1 - cos(theta) < 0.7% inside
  r < 0.12 R);
* in contact: g_i <= 1e-9 delta and p_i > 1e-9 max p (for internodes:
  active with p > 0); r_i is the distance from the pole's vertical axis
  (|x| in 2D);
* contact radius / half-width: ``a_nodes`` the largest r of a node in
  contact; ``a_interpolated`` where the pressure reaches zero between the
  last contact node i and the first free node j along each surface edge
  (i, j): the Hertz form p^2 = p_i^2 - s (r^2 - r_i^2), with s = p0^2/a^2
  from the ellipse fit below, is solved for p = 0 and clamped to
  [r_i, r_j], then averaged over those edges (in 3D the rim is ragged, so
  this mean can fall below a_nodes); ``a_midpoint`` the mean of
  (r_i + r_j)/2 over the same edges; ``a_fit`` the least-squares fit of
  p_i^2 = p0^2 - (p0^2/a^2) r_i^2 over the nodes in contact (what
  internodes' summary reports);
* interface spacing h: mean length of the candidate-surface edges whose
  two ends lie within r <= 2 a_nodes of the pole;
* Hertz values for the measured P, R from the mesh (height of the top face
  above the pole), E* = E / (1 - nu^2) (rigid flat): 3D
  a = (3PR/(4E*))^(1/3), p0 = 3P/(2 pi a^2); 2D a = sqrt(4PR/(pi E*)),
  p0 = 2P/(pi a).

Usage:
  /usr/bin/python3 validation/contact_reference.py solve MESH.msh [--delta D] [--E 1000] [--nu 0.3]
        [--fractions 0.25 0.5 0.75 1] [--kappas 1e1 1e2 ...] [--output DIR]
  /usr/bin/python3 validation/rigid_flat_comparison.py DIR/contact_reference.json INTERNODES_OUT_DIR

Meshes (the parameters of geo/hemisphere_on_block.toml, geo/half_disc_on_block.toml):
  gmsh -3 geo/hemisphere_on_block.geo -setnumber h_c 0.03 -setnumber r_c 0.2 -format msh41 -o hob.msh
  gmsh -2 geo/half_disc_on_block.geo -setnumber h_c 0.0125 -setnumber r_c 0.2 -setnumber h_far 0.5 \
       -format msh41 -o hdob.msh
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import gmsh
import numpy as np
import ufl
from dolfinx import cpp, fem
from dolfinx import mesh as dmesh
from dolfinx.fem import petsc
from mpi4py import MPI
from petsc4py import PETSc

VALIDATION = Path(__file__).resolve().parent

import hertz_theory  # noqa: E402
from dolfinx_reference import (  # noqa: E402
    ReferenceFailure,
    _gmsh_elements,
    _gmsh_model,
    _gmsh_node_positions,
    rigid_body_modes,
)

logging.disable(logging.INFO)  # silence the FFCx JIT

# Physical groups and the approach of the project's case files, by dimension.
SETUPS = {
    3: {"body": "sphere", "contact": "sphere_contact", "top": "sphere_top", "delta": 0.01},
    2: {"body": "disc", "contact": "disc_contact", "top": "disc_top", "delta": 0.02},
}
DEFAULT_FRACTIONS = (0.25, 0.5, 0.75, 1.0)
# Penalty stiffness factors of the convergence check (k_i = kappa E* A_i / h).
DEFAULT_KAPPAS = (1e1, 1e2, 1e3, 1e4, 1e5)
# A node is in contact if its gap is <= GAP_TOLERANCE delta and its pressure > PRESSURE_TOLERANCE max p.
GAP_TOLERANCE = 1e-9
PRESSURE_TOLERANCE = 1e-9
# KKT conditions of the returned solution, relative to the contact force / delta.
KKT_TOLERANCE = 1e-8


# ---------------------------------------------------------------------------
# The body's mesh, taken from the two-body gmsh file
# ---------------------------------------------------------------------------


@dataclass
class BodyMesh:
    """The nodes and cells of one physical volume / surface of a gmsh file.

    Local node a is gmsh node ``node_tags[a]`` (sorted tags); ``facets[group]``
    holds the boundary elements of a group as local node indices.
    """

    path: Path
    dim: int
    name: str
    node_tags: np.ndarray  # (n,)
    x: np.ndarray  # (n, 3)
    cells: np.ndarray  # (m, dim + 1) local node indices
    cell_tags: np.ndarray  # (m,) gmsh element tags
    facets: dict[str, np.ndarray]  # group -> (k, dim) local node indices

    @property
    def num_nodes(self) -> int:
        return len(self.node_tags)


def read_body(path: str | Path, body: str, groups: list[str]) -> BodyMesh:
    """Extract body ``body`` and its boundary ``groups`` from a two-body .msh file."""
    path = Path(path)
    if not path.is_file():
        raise ReferenceFailure(f"mesh file {path} does not exist")
    with _gmsh_model(path):
        dim = gmsh.model.getDimension()
        named = {gmsh.model.getPhysicalName(d, t): (d, t) for d, t in gmsh.model.getPhysicalGroups()}
        for name, d in [(body, dim)] + [(g, dim - 1) for g in groups]:
            if name not in named or named[name][0] != d:
                raise ReferenceFailure(f"{path}: no physical group '{name}' of dimension {d} (groups: {sorted(named)})")
        cell_tags, cell_nodes = _gmsh_elements(*named[body])
        facet_nodes = {g: _gmsh_elements(*named[g])[1] for g in groups}
        positions = _gmsh_node_positions()
    node_tags = np.unique(cell_nodes)
    local = {}
    for g, nodes in facet_nodes.items():
        index = np.searchsorted(node_tags, nodes).clip(0, len(node_tags) - 1)
        if not (node_tags[index] == nodes).all():
            raise ReferenceFailure(f"{path}: group '{g}' has nodes that are not nodes of '{body}'")
        local[g] = index
    return BodyMesh(path, dim, body, node_tags, positions[node_tags], np.searchsorted(node_tags, cell_nodes),
                    cell_tags, local)


# ---------------------------------------------------------------------------
# The dolfinx model and its solvers
# ---------------------------------------------------------------------------


@dataclass
class ContactSolution:
    """One solve, in the local node numbering of the BodyMesh."""

    delta: float
    method: str  # "vi" or "penalty kappa=..."
    u: np.ndarray  # (n, dim)
    reaction: np.ndarray  # (n, dim) K u
    iterations: int
    reason: int  # SNES converged reason (> 0: converged)
    residual_norms: list[float]
    seconds: float
    kkt: dict = field(default_factory=dict)


class RigidFlatContact:
    """The body in dolfinx, with K, the top-face dofs and the contact-surface data (set up once)."""

    def __init__(self, body: BodyMesh, contact: str, top: str, youngs_modulus: float, poisson_ratio: float,
                 obstacle=None):
        """``obstacle``: None for the flat x_v = 0; else a function of the contact nodes' coordinates
        (k, 3) returning (g0, n): each node's initial gap to a rigid obstacle's surface below it and
        that surface's unit normal there (k, dim), pointing into the body (g0 = inf where there is no
        obstacle: no constraint). The constraint is then n . u >= -g0 (small sliding: the node to
        the plane of the obstacle's facet under it), solved in rotated coordinates: at each
        constrained node the vertical dof slot carries n . u, the others the tangential components,
        which stay free (frictionless)."""
        self.body, self.contact_group, self.top_group = body, contact, top
        self.E, self.nu = youngs_modulus, poisson_ratio
        d = self.dim = body.dim
        self.v = d - 1  # the vertical component
        cell = ufl.tetrahedron if d == 3 else ufl.triangle
        self.mesh = dmesh.create_mesh(MPI.COMM_WORLD, body.cells, body.x[:, :d],
                                      ufl.Mesh(ufl.VectorElement("Lagrange", cell, 1)))
        self.V = fem.VectorFunctionSpace(self.mesh, ("CG", 1))
        self.Q = fem.FunctionSpace(self.mesh, ("CG", 1))
        self.node_of_vertex = self._node_of_vertex()
        self.vertex_of_node = np.argsort(self.node_of_vertex)
        self.facet_tags = self._facet_tags()
        self.K = self._stiffness()
        self.top_nodes = np.unique(body.facets[top])
        # candidate nodes; in 2D the ends of the arc are also on the top face and stay Dirichlet nodes
        self.contact_nodes = np.setdiff1d(np.unique(body.facets[contact]), self.top_nodes)
        self.area = self._lumped_area()
        self.top_dofs = self._dofs(self.top_nodes, range(d))
        self.contact_dofs = self._dofs(self.contact_nodes, [self.v])
        self.height = body.x[self.contact_nodes, self.v]
        self.rotation = None  # solver dofs -> displacements (None: the identity)
        if obstacle is not None:
            gap, normals = obstacle(body.x[self.contact_nodes])
            self.height = np.asarray(gap, float)
            self.normals = np.asarray(normals, float)
        # nodes with no obstacle below them carry no constraint (an infinite gap)
        self.bounded = np.isfinite(self.height)
        if (self.height[self.bounded] < -1e-14).any():
            raise ReferenceFailure(f"{body.path}: contact-surface nodes below the obstacle (initial overlap)")
        self.K_solve = self.K
        if obstacle is not None:
            self.rotation = self._rotation(self.contact_nodes[self.bounded], self.normals[self.bounded])
            self.K_solve = self.K.PtAP(self.rotation)
        self.K_bc = self.K_solve.copy()
        self.K_bc.zeroRowsColumns(self.top_dofs.astype(np.int32), diag=1.0)

    # -- set-up ---------------------------------------------------------

    def _rotation(self, nodes: np.ndarray, normals: np.ndarray) -> PETSc.Mat:
        """R with u = R x: the identity but at ``nodes``, where the vertical slot of x is n . u and
        the other slots the components along orthonormal tangents (R orthogonal)."""
        d, v = self.dim, self.v
        size = self.K.getSize()[0]
        R = PETSc.Mat().createAIJ([size, size], nnz=d)
        rotated = np.zeros(size, bool)
        for node, n in zip(nodes, normals):
            n = n[:d] / np.linalg.norm(n[:d])
            if d == 2:
                basis = [np.array([n[1], -n[0]]), n]
            else:
                helper = np.eye(3)[int(np.argmin(np.abs(n)))]
                t1 = np.cross(n, helper)
                t1 /= np.linalg.norm(t1)
                basis = [t1, np.cross(n, t1), n]
            dofs = d * self.vertex_of_node[node] + np.arange(d)
            rotated[dofs] = True
            for slot, column in enumerate(basis):  # slot v holds n, the others tangents
                R.setValues(dofs.astype(np.int32), [int(dofs[slot])], column[:, None])
        for i in np.flatnonzero(~rotated):
            R.setValue(int(i), int(i), 1.0)
        R.assemble()
        return R

    def _node_of_vertex(self) -> np.ndarray:
        """Local node (gmsh order) of each dolfinx P1 vertex dof, through input_global_indices."""
        d = self.dim
        geometry = self.mesh.geometry.dofmap.array.reshape(-1, d + 1)
        dofs = self.V.dofmap.list.array.reshape(-1, d + 1)
        if not np.array_equal(dofs, self.Q.dofmap.list.array.reshape(-1, d + 1)):
            raise ReferenceFailure("dolfinx: scalar and vector P1 dofmaps differ")
        node = np.full(self.V.dofmap.index_map.size_local, -1)
        node[dofs] = np.asarray(self.mesh.geometry.input_global_indices)[geometry]
        if (node < 0).any() or len(np.unique(node)) != self.body.num_nodes:
            raise ReferenceFailure("dolfinx vertex map to the gmsh nodes is not a bijection")
        error = abs(self.V.tabulate_dof_coordinates()[:, :d] - self.body.x[node, :d]).max()
        if error > 1e-13 * max(np.ptp(self.body.x, axis=0).max(), 1.0):
            raise ReferenceFailure(f"dolfinx vertex coordinates differ from the gmsh nodes by {error:.2e}")
        return node

    def _facet_tags(self):
        """dolfinx meshtags of the contact (1) and top (2) facets, from the gmsh elements."""
        d = self.dim
        facets = np.concatenate([self.body.facets[self.contact_group], self.body.facets[self.top_group]])
        values = np.concatenate([np.full(len(self.body.facets[self.contact_group]), 1, np.int32),
                                 np.full(len(self.body.facets[self.top_group]), 2, np.int32)])
        entities, local_values = cpp.io.distribute_entity_data(getattr(self.mesh, "_mesh", self.mesh), d - 1, facets.astype(np.int64), values)
        self.mesh.topology.create_connectivity(d - 1, 0)
        self.mesh.topology.create_connectivity(d - 1, d)
        tags = dmesh.meshtags_from_entities(self.mesh, d - 1, cpp.graph.AdjacencyList_int32(entities),
                                            local_values.astype(np.int32))
        for tag, group in ((1, self.contact_group), (2, self.top_group)):
            if (tags.values == tag).sum() != len(self.body.facets[group]):
                raise ReferenceFailure(f"{self.body.path}: not every element of '{group}' is a dolfinx facet")
        return tags

    def lame(self) -> tuple[float, float]:
        e, nu = self.E, self.nu
        return e * nu / ((1 + nu) * (1 - 2 * nu)), e / (2 * (1 + nu))

    def _stiffness(self) -> PETSc.Mat:
        """K of a(u, w) = int sigma(u) : eps(w) dx (plane strain in 2D), no boundary conditions."""
        lam, mu = self.lame()
        u, w = ufl.TrialFunction(self.V), ufl.TestFunction(self.V)
        eps = lambda f: ufl.sym(ufl.grad(f))  # noqa: E731
        sigma = 2 * mu * eps(u) + lam * ufl.tr(eps(u)) * ufl.Identity(self.dim)
        K = petsc.assemble_matrix(fem.form(ufl.inner(sigma, eps(w)) * ufl.dx))
        K.assemble()
        modes = rigid_body_modes(self.body.x[self.node_of_vertex, : self.dim])
        x, y = K.createVecs()
        worst = 0.0
        for mode in modes.T:
            x.array[:] = mode
            K.mult(x, y)
            worst = max(worst, abs(y.array).max() / abs(mode).max())
        if worst > 1e-11 * K.norm(PETSc.NormType.INFINITY):
            raise ReferenceFailure(f"dolfinx stiffness does not annihilate rigid-body modes ({worst:.2e})")
        return K

    def _lumped_area(self) -> np.ndarray:
        """A_a = sum_b int_contact phi_a phi_b ds (row sums of the P1 surface mass), per local node."""
        ds = ufl.Measure("ds", domain=self.mesh, subdomain_data=self.facet_tags)
        q = ufl.TestFunction(self.Q)
        vec = petsc.assemble_vector(fem.form(q * ds(1)))
        area = np.zeros(self.body.num_nodes)
        area[self.node_of_vertex] = vec.array
        measure = facet_measure(self.body.x[self.body.facets[self.contact_group]])
        if abs(area.sum() - measure) > 1e-11 * measure:
            raise ReferenceFailure(f"surface mass of '{self.contact_group}' sums to {area.sum()}, gmsh area {measure}")
        return area

    def _dofs(self, nodes: np.ndarray, components) -> np.ndarray:
        """PETSc dofs (block size dim) of the given local nodes and components."""
        return np.concatenate([self.dim * self.vertex_of_node[nodes] + c for c in components])

    # -- solves ---------------------------------------------------------

    def _start(self, delta: float) -> tuple[PETSc.Vec, np.ndarray]:
        """Initial guess: the top-face data, zero elsewhere; and the prescribed values g."""
        x, _ = self.K.createVecs()
        g = np.zeros(len(self.top_dofs))
        top_vertical = np.isin(self.top_dofs % self.dim, [self.v])
        g[top_vertical] = -delta
        x.set(0.0)
        x.array[self.top_dofs] = g
        return x, g

    def _residual(self, g: np.ndarray, extra=None):
        """SNES residual F(x) = K x (+ extra), with F = x - g on the top-face dofs."""

        def residual(snes, x, F):
            self.K_solve.mult(x, F)
            if extra is not None:
                F.array[:] += extra(x.array)
            F.array[self.top_dofs] = x.array[self.top_dofs] - g

        return residual

    def _snes(self, kind: str) -> PETSc.SNES:
        """SNES of the given type: full Newton steps, MUMPS LU inner solve, tight relative tolerance."""
        snes = PETSc.SNES().create(MPI.COMM_WORLD)
        prefix = f"contact_reference_{id(snes)}_"
        snes.setOptionsPrefix(prefix)
        PETSc.Options().setValue(f"{prefix}snes_linesearch_type", "basic")
        # a stiff penalty makes the residual of the first Newton iterate huge: no divergence test
        PETSc.Options().setValue(f"{prefix}snes_divergence_tolerance", -1)
        snes.setType(kind)
        snes.setTolerances(rtol=1e-12, atol=1e-30, stol=1e-30, max_it=100)
        ksp = snes.getKSP()
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        ksp.getPC().setFactorSolverType("mumps")
        snes.setFromOptions()
        return snes

    def solve(self, delta: float) -> ContactSolution:
        """Bound-constrained solve, SNES vinewtonrsls: u_v >= -x_v at the contact-surface nodes."""
        start = time.perf_counter()
        x, g = self._start(delta)
        lower, upper = x.duplicate(), x.duplicate()
        lower.set(PETSc.NINFINITY)
        upper.set(PETSc.INFINITY)
        lower.array[self.contact_dofs] = np.where(self.bounded, -self.height, PETSc.NINFINITY)
        snes = self._snes("vinewtonrsls")
        F = x.duplicate()
        snes.setFunction(self._residual(g), F)
        snes.setJacobian(lambda snes, x, J, P: None, self.K_bc)  # constant Jacobian
        snes.setVariableBounds(lower, upper)
        norms = []
        snes.setMonitor(lambda snes, it, norm: norms.append(float(norm)))
        snes.solve(None, x)
        return self._solution(delta, "vi", x, snes, norms, time.perf_counter() - start)

    def solve_penalty(self, delta: float, kappa: float, h: float) -> ContactSolution:
        """Nodal penalty: force k_i max(0, -(x_i,v + u_i,v)) upwards, k_i = kappa E* A_i / h.

        Semismooth Newton (SNES newtonls, full steps), Jacobian K + diag(k_i [penetrating]).
        """
        start = time.perf_counter()
        x, g = self._start(delta)
        k = kappa * self.E / (1 - self.nu**2) * self.area[self.contact_nodes] / h
        dofs = self.contact_dofs

        def penalty_force(u):
            f = np.zeros_like(u)
            f[dofs] = -k * np.maximum(0.0, -(self.height + u[dofs]))
            return f

        def jacobian(snes, x, J, P):
            self.K_bc.copy(J)
            diagonal = J.createVecLeft()
            diagonal.set(0.0)
            diagonal.array[dofs] = k * (self.height + x.array[dofs] < 0)
            J.setDiagonal(diagonal, addv=PETSc.InsertMode.ADD_VALUES)
            J.assemble()

        snes = self._snes("newtonls")
        F = x.duplicate()
        J = self.K_bc.duplicate(copy=True)
        snes.setFunction(self._residual(g, penalty_force), F)
        snes.setJacobian(jacobian, J)
        norms = []
        snes.setMonitor(lambda snes, it, norm: norms.append(float(norm)))
        snes.solve(None, x)
        return self._solution(delta, f"penalty kappa={kappa:g}", x, snes, norms, time.perf_counter() - start)

    def _solution(self, delta, method, x, snes, norms, seconds) -> ContactSolution:
        """Displacements and reactions K u in the local numbering, plus the KKT check (made in the
        solver's coordinates: rotated at the constrained nodes of an obstacle)."""
        d = self.dim
        r = x.duplicate()
        self.K_solve.mult(x, r)
        frame = ContactSolution(delta, method, x.array.reshape(-1, d)[self.vertex_of_node].copy(),
                                r.array.reshape(-1, d)[self.vertex_of_node].copy(), snes.getIterationNumber(),
                                snes.getConvergedReason(), norms, seconds)
        kkt = self.kkt(frame)
        if self.rotation is None:
            frame.kkt = kkt
            return frame
        u = x.duplicate()
        self.rotation.mult(x, u)
        self.K.mult(u, r)
        solution = ContactSolution(delta, method, u.array.reshape(-1, d)[self.vertex_of_node].copy(),
                                   r.array.reshape(-1, d)[self.vertex_of_node].copy(), snes.getIterationNumber(),
                                   snes.getConvergedReason(), norms, seconds, kkt)
        return solution

    def kkt(self, s: ContactSolution) -> dict:
        """The discrete contact conditions at the solution, relative to P (forces) and delta (gaps).

        stationarity: max |r| over the dofs neither on the top face nor vertical
        at a contact node; feasibility: max(0, -g); dual feasibility:
        max(0, -r_v) at contact nodes; complementarity: max |g r_v| / (delta P).
        """
        free = np.ones(s.reaction.shape, bool)
        free[self.top_nodes] = False
        bounded = self.contact_nodes[self.bounded]
        free[bounded, self.v] = False
        force = max(s.reaction[bounded, self.v].sum(), 1e-300)
        gap = self.height[self.bounded] + s.u[bounded, self.v]
        rv = s.reaction[bounded, self.v]
        figures = {
            "stationarity": float(abs(s.reaction[free]).max() / force),
            "penetration": float(max(0.0, -gap.min()) / s.delta),
            "tension": float(max(0.0, -rv.min()) / force),
            "complementarity": float(abs(gap * rv).max() / (s.delta * force)),
        }
        figures["passed"] = bool(max(figures.values()) <= KKT_TOLERANCE)
        return figures


# ---------------------------------------------------------------------------
# Post-processing
# ---------------------------------------------------------------------------


def facet_measure(x: np.ndarray) -> float:
    """Total length (segments (k, 2, 3)) or area (triangles (k, 3, 3))."""
    edges = x[:, 1:] - x[:, :1]
    if x.shape[1] == 2:
        return float(np.linalg.norm(edges[:, 0], axis=1).sum())
    return float(0.5 * np.linalg.norm(np.cross(edges[:, 0], edges[:, 1]), axis=1).sum())


def hertz(force: float, radius: float, youngs_modulus: float, poisson_ratio: float, dim: int) -> dict:
    """Hertz contact radius / half-width and peak pressure for load P on a rigid flat (``hertz_theory``)."""
    e_star = hertz_theory.contact_modulus([(youngs_modulus, poisson_ratio)])
    return hertz_theory.contact(force, radius, e_star, dim) | {"E_star": e_star}


def ellipse_fit(r: np.ndarray, p: np.ndarray) -> dict | None:
    """Least squares p^2 = c0 - s r^2 -> a = sqrt(c0 / s), p0 = sqrt(c0); None if not an ellipse."""
    if len(r) < 3:
        return None
    (c0, slope), *_ = np.linalg.lstsq(np.column_stack([np.ones_like(r), -(r**2)]), p**2, rcond=None)
    if c0 <= 0 or slope <= 0:
        return None
    return {"a": math.sqrt(c0 / slope), "p0": math.sqrt(c0), "slope": slope}


def surface_edges(facets: np.ndarray) -> np.ndarray:
    """Unique edges (e, 2) of segments or triangles (local node indices)."""
    if facets.shape[1] == 2:
        edges = facets
    else:
        edges = np.concatenate([facets[:, [0, 1]], facets[:, [1, 2]], facets[:, [2, 0]]])
    return np.unique(np.sort(edges, axis=1), axis=0)


def contact_radii(r: np.ndarray, p: np.ndarray, contact: np.ndarray, edges: np.ndarray, fit: dict | None) -> dict:
    """a_nodes, a_interpolated, a_midpoint (see the module doc) from node values indexed like r."""
    if not contact.any():
        return {"a_nodes": 0.0, "a_interpolated": None, "a_midpoint": None, "first_free": None}
    rim = edges[contact[edges[:, 0]] != contact[edges[:, 1]]]
    if len(rim) == 0:
        return {"a_nodes": float(r[contact].max()), "a_interpolated": None, "a_midpoint": None, "first_free": None}
    rim = np.where(contact[rim[:, :1]], rim, rim[:, ::-1])  # (contact node, free node)
    ri, rj, pi = r[rim[:, 0]], r[rim[:, 1]], p[rim[:, 0]]
    result = {"a_nodes": float(r[contact].max()), "a_midpoint": float(((ri + rj) / 2).mean()),
              "first_free": float(rj.min()), "rim_edges": int(len(rim))}
    if fit is not None:
        zero = np.sqrt(ri**2 + pi**2 / fit["slope"])
        result["a_interpolated"] = float(np.clip(zero, np.minimum(ri, rj), np.maximum(ri, rj)).mean())
    else:
        result["a_interpolated"] = None
    return result


def interface_spacing(x: np.ndarray, edges: np.ndarray, r: np.ndarray, radius: float) -> dict:
    """Mean / min / max length of the surface edges with both ends within r <= radius."""
    near = edges[(r[edges] <= radius).all(axis=1)]
    if len(near) == 0:
        near = edges[np.argsort(r[edges].max(axis=1))[:6]]
    length = np.linalg.norm(x[near[:, 0]] - x[near[:, 1]], axis=1)
    return {"h": float(length.mean()), "h_min": float(length.min()), "h_max": float(length.max()),
            "edges": int(len(near)), "within_r": float(radius)}


def summarize(model: RigidFlatContact, s: ContactSolution, radius: float) -> dict:
    """Force, pressure, radii and Hertz values of one solution (see the module doc)."""
    body, v, nodes = model.body, model.v, model.contact_nodes
    pole = nodes[np.argmin(body.x[nodes, v])]
    lateral = [c for c in range(model.dim) if c != v]
    axis = body.x[pole, lateral]
    r_all = np.linalg.norm(body.x[:, lateral] - axis, axis=1)
    gap = model.height + s.u[nodes, v]
    force_nodes = s.reaction[nodes, v]
    pressure = force_nodes / model.area[nodes]
    force = float(force_nodes.sum())
    contact = (gap <= GAP_TOLERANCE * s.delta) & (pressure > PRESSURE_TOLERANCE * pressure.max())
    top_reaction = s.reaction[model.top_nodes].sum(axis=0)
    fit = ellipse_fit(r_all[nodes][contact], pressure[contact])

    # radii on the surface edges: node values in the local numbering
    in_contact = np.zeros(body.num_nodes, bool)
    in_contact[nodes[contact]] = True
    p_all = np.zeros(body.num_nodes)
    p_all[nodes] = pressure
    edges = surface_edges(body.facets[model.contact_group])
    radii = contact_radii(r_all, p_all, in_contact, edges, fit)
    spacing = interface_spacing(body.x, edges, r_all, 2 * max(radii["a_nodes"], 1e-300))
    return {
        "delta": s.delta,
        "method": s.method,
        "force": force,
        "top_reaction": top_reaction.tolist(),
        "force_balance": float(abs(force + top_reaction[v]) / force),
        "lateral_force": float(np.linalg.norm(s.reaction[nodes][:, lateral].sum(axis=0)) / force),
        "nodes_in_contact": int(contact.sum()),
        "nodes_touching": int((gap <= GAP_TOLERANCE * s.delta).sum()),
        "max_pressure": float(pressure.max()),
        **radii,
        "fit": fit and {"a": fit["a"], "p0": fit["p0"]},
        "interface_spacing": spacing,
        "hertz": hertz(force, radius, model.E, model.nu, model.dim),
        "snes": {"iterations": s.iterations, "converged_reason": s.reason,
                 "residual_norms": s.residual_norms, "seconds": s.seconds},
        "kkt": s.kkt,
        "_per_node": {"r": r_all[nodes], "pressure": pressure, "reaction": force_nodes, "gap": gap,
                      "contact": contact, "pole": int(pole), "axis": axis},
    }


def node_table(model: RigidFlatContact, result: dict) -> list[dict]:
    """One row per contact-surface node: gmsh tag, coordinates, r, lumped area, reaction, pressure, gap."""
    per = result["_per_node"]
    nodes = model.contact_nodes
    return [{"tag": int(model.body.node_tags[a]), "x": model.body.x[a].tolist(), "r": float(per["r"][k]),
             "area": float(model.area[a]), "reaction": float(per["reaction"][k]),
             "pressure": float(per["pressure"][k]), "gap": float(per["gap"][k]), "contact": bool(per["contact"][k])}
            for k, a in enumerate(nodes)]


# ---------------------------------------------------------------------------
# The reference run
# ---------------------------------------------------------------------------


def turned_mesh(msh: Path, dim: int) -> Path:
    """The mesh turned upside down (``<stem>_turned.msh`` beside it, rewritten when older than the mesh):
    rotated by 180 degrees about the first horizontal axis (3D: y, z -> -y, -z; 2D: x, y -> -x, -y), so
    that the lower body of a two-equal mesh points down onto v = 0 like the upper one. A rotation, not a
    reflection: the cells keep their orientation (a reflected mesh inverts every cell)."""
    out = msh.with_name(f"{msh.stem}_turned.msh")
    if out.is_file() and out.stat().st_mtime >= msh.stat().st_mtime:
        return out
    negated = (1, 2) if dim == 3 else (0, 1)
    with _gmsh_model(msh):
        tags, coords, _ = gmsh.model.mesh.getNodes(includeBoundary=True, returnParametricCoord=False)
        for k, tag in enumerate(tags):
            x = list(coords[3 * k:3 * k + 3])
            for axis in negated:
                x[axis] = -x[axis]
            gmsh.model.mesh.setNode(int(tag), x, [])
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.write(str(out))
    return out


def obstacle_below(facets: np.ndarray, dim: int, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A rigid P1 surface (segments (k, 2, 3) / triangles (k, 3, 3)) below ``points`` (m, 3), the
    vertical axis dim - 1: for each point, the facet whose projection on the lateral plane contains
    the point's (the highest if several; a point on a shared edge or vertex belongs to every facet
    there, barycentric tolerance 1e-9), its unit normal n pointing up (n_v > 0) and the point's
    distance n . (x - p0) from the facet's plane; (inf, e_v) where no facet is below or above."""
    v = dim - 1
    m = len(points)
    best = np.full(m, -np.inf)  # height of the surface under the point
    gap = np.full(m, np.inf)
    normals = np.zeros((m, dim))
    normals[:, v] = 1.0
    scale = max(np.abs(facets[..., :dim]).max(), 1.0)
    if dim == 2:
        for a, b in zip(facets[:, 0, :2], facets[:, 1, :2]):
            span = b[0] - a[0]
            if abs(span) <= 1e-12 * scale:
                continue
            t = (points[:, 0] - a[0]) / span
            inside = (t >= -1e-9) & (t <= 1 + 1e-9)
            s = a[1] + np.clip(t, 0, 1) * (b[1] - a[1])
            take = inside & (s > best)
            n = np.array([-(b[1] - a[1]), b[0] - a[0]])
            n = n / np.linalg.norm(n) * np.sign(n[1])
            best[take] = s[take]
            normals[take] = n
            gap[take] = (points[take, :2] - a) @ n
        return gap, normals
    p = facets[:, :, :2]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    lo, hi = p.min(axis=1) - 1e-9 * scale, p.max(axis=1) + 1e-9 * scale
    for k in np.flatnonzero(np.abs(det) > 1e-12 * scale**2):
        near = np.flatnonzero((points[:, 0] >= lo[k, 0]) & (points[:, 0] <= hi[k, 0])
                              & (points[:, 1] >= lo[k, 1]) & (points[:, 1] <= hi[k, 1]))
        if len(near) == 0:
            continue
        d = points[near, :2] - p[k, 0]
        b1 = (d[:, 0] * e2[k, 1] - d[:, 1] * e2[k, 0]) / det[k]
        b2 = (e1[k, 0] * d[:, 1] - e1[k, 1] * d[:, 0]) / det[k]
        b0 = 1 - b1 - b2
        z = facets[k, :, 2]
        s = b0 * z[0] + b1 * z[1] + b2 * z[2]
        take = (b0 >= -1e-9) & (b1 >= -1e-9) & (b2 >= -1e-9) & (s > best[near])
        rows = near[take]
        n = np.cross(facets[k, 1] - facets[k, 0], facets[k, 2] - facets[k, 0])
        n = n / np.linalg.norm(n) * np.sign(n[2])
        best[rows] = s[take]
        normals[rows] = n
        gap[rows] = (points[rows] - facets[k, 0]) @ n
    return gap, normals


def lifted_mesh(msh: Path, dim: int, shift: float) -> Path:
    """The mesh moved up by ``shift`` along the vertical axis (``<stem>_lifted<shift>.msh`` beside it,
    rewritten when older than the mesh): the curved body of a mesh made overlapping (geo ``gap < 0``),
    lifted by -gap, is the same discrete body with its pole on the flat, which the reference needs."""
    out = msh.with_name(f"{msh.stem}_lifted{shift:g}.msh")
    if out.is_file() and out.stat().st_mtime >= msh.stat().st_mtime:
        return out
    with _gmsh_model(msh):
        tags, coords, _ = gmsh.model.mesh.getNodes(includeBoundary=True, returnParametricCoord=False)
        for k, tag in enumerate(tags):
            x = list(coords[3 * k:3 * k + 3])
            x[dim - 1] += shift
            gmsh.model.mesh.setNode(int(tag), x, [])
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.write(str(out))
    return out


# Approaches of each body alone, as fractions of the pair's delta: each takes about half of it.
PAIR_FRACTIONS = (0.35, 0.45, 0.5, 0.55, 0.65)


def two_body_plane(msh: Path, dim: int, delta: float, bodies: dict, cache: Path, youngs_modulus: float,
                   poisson_ratio: float) -> dict:
    """Where two bodies of equal material, pressed together by ``delta``, meet: the plane of their interface.

    ``bodies`` maps "upper" and "lower" to (body, contact surface, support) groups of ``msh``: the upper
    body's pole down at v = 0, its support moved by -delta; the lower body's pole up at v = 0, its
    support clamped. Between equal materials the frictionless interface is flat, so each body deforms
    as on a rigid flat under the same force P. Each is pressed alone onto a rigid flat (the lower one
    on the mesh turned upside down) at approaches PAIR_FRACTIONS of delta; P solves
    delta_upper(P) + delta_lower(P) = delta (log-log interpolation of each approach-force curve), and
    the interface lies at v = -delta_lower(P). With two different meshes the two discrete bodies differ
    in stiffness, and the plane is not v = -delta/2. Each body's curve is cached in ``cache``.
    """
    curves = {}
    for role in ("upper", "lower"):
        body, contact, support = bodies[role]
        source = msh if role == "upper" else turned_mesh(msh, dim)
        stamp_data = {"mesh": source.name, "mesh_size": msh.stat().st_size, "mesh_mtime": msh.stat().st_mtime,
                      "delta": delta, "fractions": PAIR_FRACTIONS, "E": youngs_modulus, "nu": poisson_ratio,
                      "body": body}
        folder = cache / f"{msh.stem}_{role}_delta{delta:g}"
        stamp, result = folder / "stamp.json", folder / "contact_reference.json"
        if stamp.is_file() and result.is_file() and json.loads(stamp.read_text()) == stamp_data:
            data = json.loads(result.read_text())
        else:
            data = run_reference(source, folder, delta=delta, youngs_modulus=youngs_modulus,
                                 poisson_ratio=poisson_ratio, fractions=PAIR_FRACTIONS, kappas=(),
                                 groups={"body": body, "contact": contact, "top": support})
            stamp.write_text(json.dumps(stamp_data))
        points = sorted((r["delta"], r["force"]) for r in data["force_approach"] if r["force"] > 0)
        curves[role] = (np.log([d for d, _ in points]), np.log([f for _, f in points]))

    def approach(role: str, force: float) -> float:
        log_delta, log_force = curves[role]
        return float(np.exp(np.interp(math.log(force), log_force, log_delta)))

    def excess(force: float) -> float:
        return approach("upper", force) + approach("lower", force) - delta

    low = max(math.exp(c[1][0]) for c in curves.values())
    high = min(math.exp(c[1][-1]) for c in curves.values())
    if not excess(low) < 0 < excess(high):
        raise ReferenceFailure(f"{msh}: the approach {delta:g} of the pair is not bracketed by the bodies' "
                               f"rigid-flat curves (forces {low:.4g} to {high:.4g})")
    for _ in range(100):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if excess(middle) < 0 else (low, middle)
    force = 0.5 * (low + high)
    return {"force": force, "delta_upper": approach("upper", force), "delta_lower": approach("lower", force),
            "plane": -approach("lower", force)}


def run_reference(msh: Path, output: Path, delta: float | None = None, youngs_modulus: float = 1000.0,
                  poisson_ratio: float = 0.3, fractions=DEFAULT_FRACTIONS, kappas=DEFAULT_KAPPAS,
                  groups: dict | None = None) -> dict:
    """Solve, check, write ``output/contact_reference.json`` and the two plots; return the JSON data."""
    timings = {}
    start = time.perf_counter()
    with _gmsh_model(Path(msh)):
        dim = gmsh.model.getDimension()
    if dim not in SETUPS:
        raise ReferenceFailure(f"{msh}: dimension {dim}, expected 2 or 3")
    setup = {**SETUPS[dim], **(groups or {})}
    delta = setup["delta"] if delta is None else delta
    body = read_body(msh, setup["body"], [setup["contact"], setup["top"]])
    timings["read mesh"] = time.perf_counter() - start

    start = time.perf_counter()
    model = RigidFlatContact(body, setup["contact"], setup["top"], youngs_modulus, poisson_ratio)
    v = model.v
    radius = float(body.x[model.top_nodes, v].mean() - body.x[model.contact_nodes, v].min())
    timings["dolfinx set-up"] = time.perf_counter() - start

    start = time.perf_counter()
    steps = []
    for fraction in sorted(set(fractions) | {1.0}):
        solution = model.solve(fraction * delta)
        steps.append((fraction, solution, summarize(model, solution, radius)))
    timings["VI solves"] = time.perf_counter() - start
    final_solution, final = steps[-1][1], steps[-1][2]

    start = time.perf_counter()
    penalty = []
    h = final["interface_spacing"]["h"]
    for kappa in kappas:
        s = model.solve_penalty(delta, kappa, h)
        force = float(s.reaction[model.contact_nodes, v].sum())
        gap = model.height + s.u[model.contact_nodes, v]
        penalty.append({"kappa": kappa, "force": force,
                        "relative_difference_to_vi": abs(force - final["force"]) / final["force"],
                        "max_penetration_over_delta": float(max(0.0, -gap.min()) / delta),
                        "max_displacement_difference_over_delta":
                            float(abs(s.u - final_solution.u).max() / delta),
                        "iterations": s.iterations, "converged_reason": s.reason, "seconds": s.seconds})
    timings["penalty check"] = time.perf_counter() - start

    data = {
        "mesh": str(Path(msh).resolve()),
        "dimension": dim,
        "body": setup["body"],
        "contact_surface": setup["contact"],
        "top_surface": setup["top"],
        "youngs_modulus": youngs_modulus,
        "poisson_ratio": poisson_ratio,
        "radius": radius,
        "num_nodes": body.num_nodes,
        "num_cells": len(body.cells),
        "num_contact_surface_nodes": len(model.contact_nodes),
        "num_dofs": dim * body.num_nodes,
        "contact_facets": body.node_tags[body.facets[setup["contact"]]].tolist(),
        "axis": final["_per_node"]["axis"].tolist(),
        "solution": {k: val for k, val in final.items() if k != "_per_node"},
        "force_approach": [{"fraction": f, "delta": s.delta, "force": res["force"], "a_nodes": res["a_nodes"],
                            "a_fit": res["fit"] and res["fit"]["a"], "nodes_in_contact": res["nodes_in_contact"],
                            "hertz_force_for_delta": hertz_force(s.delta, radius, youngs_modulus, poisson_ratio, dim),
                            "iterations": s.iterations, "converged_reason": s.reason, "kkt_passed": res["kkt"]["passed"],
                            "seconds": s.seconds}
                           for f, s, res in steps],
        "penalty_check": penalty,
        "nodes": node_table(model, final),
        "timings": timings,
    }
    if dim == 3 and len(steps) >= 2:
        d_, p_ = np.array([[s.delta, res["force"]] for _, s, res in steps]).T
        data["force_approach_exponent"] = float(np.polyfit(np.log(d_), np.log(p_), 1)[0])
    output.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    data["plots"] = {"pressure": str(output / "pressure_profile.png"),
                     "force_approach": str(output / "force_approach.png")}
    plot_profile(data, Path(data["plots"]["pressure"]))
    plot_force_approach(data, Path(data["plots"]["force_approach"]))
    timings["plots"] = time.perf_counter() - start
    (output / "contact_reference.json").write_text(json.dumps(data, indent=1) + "\n")
    return data


def hertz_force(delta: float, radius: float, youngs_modulus: float, poisson_ratio: float, dim: int) -> float | None:
    """3D Hertz load for approach delta on a rigid flat (``hertz_theory.force_3d``); None in 2D (no closed form)."""
    if dim != 3:
        return None
    return hertz_theory.force_3d(delta, radius, hertz_theory.contact_modulus([(youngs_modulus, poisson_ratio)]))


# ---------------------------------------------------------------------------
# Plots
# ---------------------------------------------------------------------------


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _coordinate(data: dict, rows: list[dict]) -> tuple[np.ndarray, str]:
    """Plot abscissa: signed x in 2D, r in 3D."""
    if data["dimension"] == 2:
        return np.array([row["x"][0] - data["axis"][0] for row in rows]), "x"
    return np.array([row["r"] for row in rows]), "r"


def _hertz_curve(ax, data: dict, label: str):
    h = data["solution"]["hertz"]
    a, p0 = h["a"], h["p0"]
    s = np.linspace(-a if data["dimension"] == 2 else 0.0, a, 201)
    ax.plot(s, p0 * np.sqrt(np.maximum(0.0, 1 - s**2 / a**2)), "k-", lw=1, label=label)


def plot_profile(data: dict, path: Path) -> None:
    """Nodal pressure against r (3D) or x (2D), with the Hertz ellipse of the measured force."""
    plt = _pyplot()
    rows = data["nodes"]
    s, name = _coordinate(data, rows)
    p = np.array([row["pressure"] for row in rows])
    keep = np.abs(s) <= 2.5 * data["solution"]["hertz"]["a"]
    sol = data["solution"]
    fig, ax = plt.subplots(figsize=(7, 4.5))
    _hertz_curve(ax, data, f"Hertz, P = {sol['force']:.4g}: a = {sol['hertz']['a']:.4f}, "
                           f"p0 = {sol['hertz']['p0']:.4g}")
    ax.plot(s[keep], p[keep], "o", ms=4, mfc="none", label="dolfinx VI, p_i = r_i / A_i")
    for sign in ([-1, 1] if data["dimension"] == 2 else [1]):
        ax.axvline(sign * sol["a_nodes"], color="C1", ls=":", lw=1)
        if sol["a_interpolated"]:
            ax.axvline(sign * sol["a_interpolated"], color="C2", ls="--", lw=1)
    ax.plot([], [], color="C1", ls=":", label=f"a_nodes = {sol['a_nodes']:.4f}")
    if sol["a_interpolated"]:
        ax.plot([], [], color="C2", ls="--", label=f"a_interpolated = {sol['a_interpolated']:.4f}")
    ax.set_xlabel(name)
    ax.set_ylabel("contact pressure")
    ax.set_title(f"{data['body']} on a rigid flat, delta = {sol['delta']:g}, h = {sol['interface_spacing']['h']:.4f}")
    ax.legend(fontsize=8, loc="upper right")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_force_approach(data: dict, path: Path) -> None:
    """P(delta) of the reference (and the 3D Hertz curve, for information)."""
    plt = _pyplot()
    steps = data["force_approach"]
    d = np.array([s["delta"] for s in steps])
    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.plot(np.r_[0.0, d], [0.0] + [s["force"] for s in steps], "o-", label="dolfinx VI (P = 0 at delta = 0: gap 0)")
    if data["dimension"] == 3:
        dd = np.linspace(0, d.max(), 101)
        ax.plot(dd, [hertz_force(x, data["radius"], data["youngs_modulus"], data["poisson_ratio"], 3) for x in dd],
                "k--", lw=1, label="Hertz (half-space), 4/3 E* R^1/2 delta^3/2")
    finish_force_approach_plot(fig, ax, f"{data['body']} on a rigid flat: force against approach",
                               data["dimension"], path)


def finish_force_approach_plot(fig, ax, title: str, dim: int, path: Path) -> None:
    """Axis labels, title, legend and grid of a P(delta) plot; writes it to ``path``."""
    ax.set_xlabel("approach delta (displacement of the curved body's top face)")
    ax.set_ylabel("contact force P" + (" per unit length" if dim == 2 else ""))
    ax.set_title(title)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    _pyplot().close(fig)


# ---------------------------------------------------------------------------
# Command line
# ---------------------------------------------------------------------------


def _fmt(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.5f}"


def report(data: dict) -> str:
    """A few lines for the terminal."""
    s = data["solution"]
    lines = [f"{data['body']} ({data['dimension']}D): {data['num_nodes']} nodes, {data['num_cells']} cells, "
             f"{data['num_contact_surface_nodes']} contact-surface nodes, R = {data['radius']:.6g}, "
             f"h = {s['interface_spacing']['h']:.4g}",
             f"delta = {s['delta']:g}: P = {s['force']:.6g} (top reaction balance {s['force_balance']:.1e}), "
             f"{s['nodes_in_contact']} nodes in contact",
             f"  a_nodes = {s['a_nodes']:.5f}, a_interpolated = {_fmt(s['a_interpolated'])}, "
             f"a_midpoint = {_fmt(s['a_midpoint'])}, "
             f"a_fit = {s['fit'] and round(s['fit']['a'], 5)}, Hertz a = {s['hertz']['a']:.5f}",
             f"  p_max = {s['max_pressure']:.5g}, p0_fit = {s['fit'] and round(s['fit']['p0'], 5)}, "
             f"Hertz p0 = {s['hertz']['p0']:.5g}",
             f"  SNES vinewtonrsls: {s['snes']['iterations']} iterations, reason {s['snes']['converged_reason']}; "
             f"KKT " + ", ".join(f"{k} {v:.1e}" for k, v in s["kkt"].items() if k != "passed")]
    for st in data["force_approach"]:
        lines.append(f"  P({st['delta']:.4g}) = {st['force']:.6g}  ({st['iterations']} its, reason "
                     f"{st['converged_reason']}, KKT {'ok' if st['kkt_passed'] else 'FAILED'}, {st['seconds']:.2f} s)")
    for pen in data["penalty_check"]:
        lines.append(f"  penalty kappa = {pen['kappa']:.0e}: P = {pen['force']:.6g}, |P - P_vi| / P_vi = "
                     f"{pen['relative_difference_to_vi']:.2e}, penetration / delta = "
                     f"{pen['max_penetration_over_delta']:.2e} ({pen['iterations']} its, reason {pen['converged_reason']})")
    lines.append("  timings: " + ", ".join(f"{k} {t:.2f} s" for k, t in data["timings"].items()))
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    solve = sub.add_parser("solve", help="compute the reference from a two-body .msh")
    solve.add_argument("mesh", type=Path)
    solve.add_argument("--delta", type=float, help="approach (default 0.01 in 3D, 0.02 in 2D)")
    solve.add_argument("--E", type=float, default=1000.0, help="Young's modulus of the body [1000]")
    solve.add_argument("--nu", type=float, default=0.3, help="Poisson ratio of the body [0.3]")
    solve.add_argument("--fractions", type=float, nargs="+", default=DEFAULT_FRACTIONS,
                       help="fractions of delta for the force-approach curve [0.25 0.5 0.75 1]")
    solve.add_argument("--kappas", type=float, nargs="*", default=DEFAULT_KAPPAS,
                       help="penalty factors of the convergence check (none: skip) [1e1 .. 1e5]")
    solve.add_argument("--body", help="physical volume / surface of the body")
    solve.add_argument("--contact", help="its candidate contact surface")
    solve.add_argument("--top", help="its face with the imposed displacement")
    solve.add_argument("--output", type=Path, help="output folder [validation/build/contact_reference/<mesh stem>]")
    args = parser.parse_args(argv)
    try:
        groups = {k: getattr(args, k) for k in ("body", "contact", "top") if getattr(args, k)}
        output = args.output or VALIDATION / "build" / "contact_reference" / args.mesh.stem
        data = run_reference(args.mesh, output, args.delta, args.E, args.nu, args.fractions, args.kappas, groups)
        print(report(data))
        print(f"wrote {output / 'contact_reference.json'} and {', '.join(data['plots'].values())}")
        ok = data["solution"]["kkt"]["passed"] and data["solution"]["snes"]["converged_reason"] > 0
        return 0 if ok else 1
    except (ReferenceFailure, OSError, KeyError) as error:
        print(f"error: {type(error).__name__}: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
