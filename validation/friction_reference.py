#!/usr/bin/python3
"""Independent frictional two-body contact reference (2D, plane strain): Coulomb friction between the
half-disc and the block of ``geo/half_disc_on_block.geo``, along a load path.

Problem. Both bodies of the gmsh mesh -- the half-disc ("disc", radius R = 1, its flat top
"disc_top", its lower arc "disc_contact") and the block ("block", its top "block_contact", its base
"block_base") -- exactly the gmsh nodes and triangles of their physical groups, are read into one
dolfinx mesh (``dolfinx_reference.ReferenceModel``, which owes nothing to internodes), and each
body's stiffness K1, K2 is assembled by dolfinx/UFL (P1, small-strain isotropic elasticity, plane
strain, E and nu per body). Dirichlet conditions: disc_top displaced by (ux, uy) at each step, the
block's base clamped. No other load.

Contact: node to segment, from the disc's candidate nodes (the nodes of "disc_contact" not on
"disc_top", within ``reach`` of the block's top in the reference configuration) onto the block's top
surface (P1 segments). At candidate node i, with b_k the P1 weights of its closest point on the block
segment under it, m the segment's unit normal (out of the block) and t = (m_y, -m_x) its unit
tangent (t = (1, 0) on the undeformed block),

    g_i   = m . (X_i + u_i - sum_k b_k (Y_k + u_k))           gap (>= 0)
    s_i   = t . (u_i - sum_k b_k u_k)                           relative tangential displacement
    v_i   = s_i - s_i(start of the step)                         slip increment over the step

and the nodal contact force on the disc lambda_n,i m + lambda_t,i t (the block receives its opposite,
spread by b_k). The discrete Coulomb conditions (nodal, the interface mass lumped):

    g_i >= 0,  lambda_n,i >= 0,  g_i lambda_n,i = 0                   (normal)
    |lambda_t,i| <= mu lambda_n,i;  |lambda_t,i| < mu lambda_n,i => v_i = 0   (stick)
                                    |lambda_t,i| = mu lambda_n,i => lambda_t,i v_i <= 0  (slip,
                                    against the slip)

and the equilibrium of both bodies K u = B_n^T lambda_n + B_t^T lambda_t on the free dofs. Nodal
tractions are forces over the lumped area A_i of the node on "disc_contact" (row sums of the P1
surface mass, dolfinx): p_i = lambda_n,i / A_i, q_i = lambda_t,i / A_i. P = sum lambda_n, Q = sum
lambda_t (on the disc). Quasi-static: each load step starts from the state (displacements, stick /
slip / open partition) the last one ended in; v is the slip increment relative to the previous step.

Pairing (``normal``):

* ``"reference"`` (default; the small-deformation theory of Hertz, Cattaneo, Mindlin and Johnson):
  closest point and normal in the reference configuration, m = (0, 1), t = (1, 0), b_k from the
  vertical projection of X_i; the constraints are linear.
* ``"deformed"``: the closest point, the segment, its normal and tangent on the deformed surfaces
  (as a node-to-segment code measures the gap, and as internodes does: docs/method.md 3.1, 3.2),
  recomputed from the answer until they stop changing (a fixed point on the geometry; the
  displacements change by less than 1e-10 of the approach at its end). The cone then acts about
  the deformed interface's normal, which on two equal bodies turns by about x / (2R) across the
  zone (up to 0.055 rad at its edge). The difference of the two pairings is the size of that
  geometric effect, which Johnson's closed form neglects.
* ``"smoothed"``: as ``"deformed"``, but the normal is interpolated (with the weights b_k) from the
  block top's nodal normals, each the mean of its two facets' normals, instead of the facet's own.
  A second, equally consistent discretization of the contact normal: the difference from
  ``"deformed"`` measures how much the answer owes to that choice. It matters at the stick nodes
  at the rim of the zone: a node that closes its initial gap g0 (about x^2 / 2R, 0.005 at x = 0.1)
  along a normal tilted by theta moves by g0 theta along the tangent, as much as the elastic
  tangential displacements there (1e-4), so a normal turned by the kink of the P1 surface at a
  block vertex (about h / 2R, 0.012 at R/40) changes that node's tangential traction by its own
  size; and those tractions, left by the press, are carried into the shear steps.

Method, and why. A primal-dual active set method on the nodes: the semismooth Newton method of the
Alart-Curnier / Hueber-Stadler-Wohlmuth nodal complementarity functions

    C_n = lambda_n - max(0, lambda_n - c g),
    C_t = lambda_t - proj_[-mu sigma, mu sigma](lambda_t - c v),   sigma = max(0, lambda_n - c g),

with c = E* A_i / h_i. In 2D both are piecewise linear in (u, lambda), so each Newton step is the
solution of the linear saddle-point system of one partition -- open (lambda_n = lambda_t = 0), stick
(g = 0, v = 0), slip along d = +-1 (g = 0, lambda_t = mu d lambda_n) -- and the update reads the new
partition off the answer: in contact if sigma > 0; then stick if |lambda_t - c v| < mu sigma, else
slip along d = sign(lambda_t - c v). The saddle-point system (both bodies' K with the Dirichlet rows
eliminated by identity rows, the constraint rows, the multiplier columns; unsymmetric where nodes
slip) is assembled with scipy.sparse and factored by SuperLU (``scipy.sparse.linalg.splu``). Why
this method: (1) it imposes the constraints exactly, with Lagrange multipliers, so its answer *is*
the discrete Coulomb problem, with no penalty parameter to drive to a limit (c only steers the
updates: it drops out of the answer); (2) on a piecewise linear problem the iteration ends in a
finite number of steps at a partition that reproduces itself, and its answer is then certified by
checking every discrete KKT condition above directly, independently of how it was found; (3) the
problem is small (a few thousand dofs), so a direct sparse LU per partition costs milliseconds. A
partition seen before (cycling) switches to single updates (only the node with the largest
violation changes), and the step fails with ``ReferenceFailure`` if that does not settle either.

Certificate (``kkt``, every step): equilibrium residual of the free dofs over the largest nodal
contact force; penetration max(0, -g) / h; tension max(0, -lambda_n) / max lambda_n;
complementarity max |lambda_n g| / (max lambda_n h); the cone max(|lambda_t| - mu lambda_n) /
(mu max lambda_n); stick max |v| / h over the nodes inside the cone; slip max(0, lambda_t v) /
(max lambda_n h) over the nodes on its edge; all within ``KKT_TOLERANCE``. Candidates: every disc
contact node outside the candidate set must stay above the block (``uncovered``).

Self-validation (``verify``): equal materials (E = 1000, nu = 0.3), pressed by 0.02 and sheared by
ux = 0.002, 0.004, 0.006 at constant approach (mu = 0.3), at h_c = 0.025, 0.0125 and 0.00625, against
Johnson's closed form (Contact Mechanics, 1985, 7.1 and 5.6; cylinders, plane strain): for equal
materials the shear does not change the pressure (Hertz: a = sqrt(4 P R / (pi E*)), p0 = 2 P / (pi
a)), the stick zone is |x| < c = a sqrt(1 - Q / (mu P)), and

    q(x) = mu p0 sqrt(1 - x^2/a^2) - mu p0 (c/a) sqrt(1 - x^2/c^2)    |x| < c
    q(x) = mu p0 sqrt(1 - x^2/a^2)                                      c <= |x| <= a.

The figures (stick half-width against c, q against the closed form, P against the pressure's
Hertz values) are printed and written to ``DIR/friction_reference_verify.json`` with a figure.
Measured (both pairings, 9 shear steps each; Q / (mu P) = 0.21, 0.41, 0.60 at ux = 0.002, 0.004,
0.006, so the path reaches the partial slip it was meant to): every step's KKT conditions hold to
5e-13; the stick half-width is within 0.61 spacings of Johnson's c at every step and spacing (0.00
to 0.61 h); the peak pressure within 0.6% of Hertz's p0 for the measured P and the outermost
contact node within 0.55 h of Hertz's a. The traction q(x) follows the closed form with an rms
difference of 0.055 to 0.115 mu p0 over the zone; the largest nodal difference, 0.09 to 0.33 mu p0,
sits at the node next to the stick-slip boundary x = +-c, where the closed form has a square-root
cusp that P1 nodal values cannot follow (it does not shrink with h). The rest is the press: in one
step every node that comes into contact sticks where it touched, and on these finite bodies (not
half-spaces) that leaves tangential tractions odd in x, up to 0.28 mu p0 at the rim's stick nodes
(linear pairing; 0.11 mu p0 when the press is made in 20 steps), which Johnson's theory, for equal
half-spaces, does not have; they skew the profile at ux = 0.002 and fade as the slip zones grow.

Usage:
  /usr/bin/python3 validation/friction_reference.py solve MESH.msh [--approach 0.02] [--shear 0.002 0.004 0.006]
        [--E1 1000 --nu1 0.3 --E2 1000 --nu2 0.3] [--mu 0.3] [--normal reference|deformed] [--output DIR]
  /usr/bin/python3 validation/friction_reference.py verify [--output DIR]
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl

VALIDATION = Path(__file__).resolve().parent
REPO = VALIDATION.parent
sys.path.insert(0, str(VALIDATION))

import hertz_theory  # noqa: E402
from contact_reference import ReferenceFailure, read_body  # noqa: E402
from dolfinx_reference import Body, ReferenceModel  # noqa: E402

logging.disable(logging.INFO)  # silence the FFCx JIT

RADIUS = 1.0  # the half-disc's radius (geo default)
# Discrete KKT conditions, relative (module doc).
KKT_TOLERANCE = 1e-8
# Round-off slack of the stick / slip test at the cone's edge, a fraction of mu max lambda_n.
CONE_SLACK = 1e-10
MAX_ITERATIONS = 200
MAX_OUTER = 60
STATE_NAMES = {0: "open", 1: "stick", 2: "slip"}
NORMALS = ("reference", "deformed", "smoothed")


@dataclass
class Pairing:
    """Each candidate's segment (block-local nodes k0, k1), weights (b0, b1), normal m, tangent t."""

    segment: np.ndarray  # (nc,) index into the block's contact segments
    nodes: np.ndarray  # (nc, 2) block-local node indices
    weights: np.ndarray  # (nc, 2)
    normal: np.ndarray  # (nc, 2)
    tangent: np.ndarray  # (nc, 2)


@dataclass
class StepState:
    """The state a step ends in (and the next one starts from)."""

    u: np.ndarray  # (N,) all dofs, disc first
    lambda_n: np.ndarray  # (nc,)
    lambda_t: np.ndarray  # (nc,)
    state: np.ndarray  # (nc,) 0 open, 1 stick, 2 slip
    direction: np.ndarray  # (nc,) +-1 for slipping nodes (sign of lambda_t), 0 otherwise


class FrictionReference:
    """The two bodies in dolfinx, K, the candidates and the solver (module doc)."""

    def __init__(self, msh: Path, disc: tuple[float, float], block: tuple[float, float], mu: float,
                 normal: str = "reference", reach: float = 0.08):
        if normal not in NORMALS:
            raise ValueError(f"normal must be one of {NORMALS}, not {normal!r}")
        self.msh, self.mu, self.normal_mode = Path(msh), float(mu), normal
        self.materials = {"disc": disc, "block": block}
        self.disc = read_body(msh, "disc", ["disc_contact", "disc_top"])
        self.block = read_body(msh, "block", ["block_contact", "block_base"])
        if self.disc.dim != 2:
            raise ReferenceFailure(f"{msh}: the friction reference is 2D (plane strain); the mesh is {self.disc.dim}D")
        model = ReferenceModel(msh, {"disc": self.disc.x, "block": self.block.x})
        K1 = model.stiffness(Body("disc", *disc))
        K2 = model.stiffness(Body("block", *block))
        self.K = sp.block_diag([K1, K2]).tocsr()
        self.n1, self.n2 = self.disc.num_nodes, self.block.num_nodes
        self.N = 2 * (self.n1 + self.n2)
        self.e_star = hertz_theory.contact_modulus([disc, block])
        # lumped areas of the disc's contact nodes (row sums of dolfinx's P1 surface mass)
        self.area_all = np.asarray(model.surface_mass("disc", "disc_contact").sum(axis=1)).ravel()
        # Dirichlet dofs
        self.top = np.unique(self.disc.facets["disc_top"])
        base = np.unique(self.block.facets["block_base"])
        self.top_dofs = np.concatenate([2 * self.top, 2 * self.top + 1])
        self.base_dofs = 2 * self.n1 + np.concatenate([2 * base, 2 * base + 1])
        self.prescribed = np.zeros(self.N, bool)
        self.prescribed[self.top_dofs] = True
        self.prescribed[self.base_dofs] = True
        # the block's top: a straight line y = 0 in the reference configuration
        self.segments = self.block.facets["block_contact"]
        top_y = self.block.x[np.unique(self.segments), 1]
        if np.abs(top_y).max() > 1e-12:
            raise ReferenceFailure(f"{msh}: the block's top is not the line y = 0")
        # candidates
        surface = np.setdiff1d(np.unique(self.disc.facets["disc_contact"]), self.top)
        if (self.disc.x[surface, 1] < -1e-12).any():
            raise ReferenceFailure(f"{msh}: disc contact nodes below the block's top (initial overlap)")
        self.surface = surface
        self.nodes = surface[self.disc.x[surface, 1] <= reach]
        self.nodes = self.nodes[np.argsort(self.disc.x[self.nodes, 0])]
        self.others = np.setdiff1d(surface, self.nodes)
        self.nc = len(self.nodes)
        self.X = self.disc.x[self.nodes, :2]
        self.area = self.area_all[self.nodes]
        self.h = self._local_spacing()
        self.c = self.e_star * self.area / self.h
        self.reference_pairing = self._pair_reference()
        top_nodes = np.unique(self.segments)
        self.pair_dofs = np.concatenate([2 * self.nodes, 2 * self.nodes + 1, 2 * self.n1 + 2 * top_nodes,
                                         2 * self.n1 + 2 * top_nodes + 1])

    # -- geometry --------------------------------------------------------

    def _local_spacing(self) -> np.ndarray:
        """Mean length of the disc contact edges at each candidate."""
        edges = self.disc.facets["disc_contact"]
        length = np.linalg.norm(self.disc.x[edges[:, 0]] - self.disc.x[edges[:, 1]], axis=1)
        total = np.zeros(self.n1)
        count = np.zeros(self.n1)
        for k in range(2):
            np.add.at(total, edges[:, k], length)
            np.add.at(count, edges[:, k], 1)
        return total[self.nodes] / count[self.nodes]

    def _pair_reference(self) -> Pairing:
        """Vertical projection of each candidate onto the undeformed block top (y = 0)."""
        xb = self.block.x[self.segments, 0]  # (ns, 2)
        lo, hi = xb.min(axis=1), xb.max(axis=1)
        seg = np.empty(self.nc, int)
        for i, x in enumerate(self.X[:, 0]):
            inside = np.flatnonzero((lo - 1e-14 <= x) & (x <= hi + 1e-14))
            if len(inside) == 0:
                raise ReferenceFailure(f"disc node at x = {x} is beyond the block's top")
            seg[i] = inside[0]
        k = self.segments[seg]
        t = (self.X[:, 0] - self.block.x[k[:, 0], 0]) / (self.block.x[k[:, 1], 0] - self.block.x[k[:, 0], 0])
        weights = np.column_stack([1 - t, t])
        normal = np.tile([0.0, 1.0], (self.nc, 1))
        tangent = np.tile([1.0, 0.0], (self.nc, 1))
        return Pairing(seg, k, weights, normal, tangent)

    def positions(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Deformed coordinates (disc, block), (n, 2) each."""
        xd = self.disc.x[:, :2] + u[: 2 * self.n1].reshape(-1, 2)
        xb = self.block.x[:, :2] + u[2 * self.n1:].reshape(-1, 2)
        return xd, xb

    def _closest(self, points: np.ndarray, xb: np.ndarray):
        """Closest point of each point on the deformed block top: (segment, t, distance)."""
        a, b = xb[self.segments[:, 0]], xb[self.segments[:, 1]]
        ab = b - a
        t = np.clip(((points[:, None, :] - a[None]) * ab[None]).sum(-1) / (ab**2).sum(-1)[None], 0.0, 1.0)
        closest = a[None] + t[..., None] * ab[None]
        distance = np.linalg.norm(points[:, None, :] - closest, axis=-1)
        seg = distance.argmin(axis=1)
        rows = np.arange(len(points))
        return seg, t[rows, seg], distance[rows, seg]

    def _pair_deformed(self, u: np.ndarray) -> Pairing:
        """Closest point on the deformed block top, the deformed segment's normal (module doc)."""
        xd, xb = self.positions(u)
        seg, t, _ = self._closest(xd[self.nodes], xb)
        k = self.segments[seg]
        ab = xb[k[:, 1]] - xb[k[:, 0]]
        ab /= np.linalg.norm(ab, axis=1)[:, None]
        normal = np.column_stack([-ab[:, 1], ab[:, 0]])
        normal *= np.sign(normal[:, 1])[:, None]  # out of the block: upwards
        weights = np.column_stack([1 - t, t])
        if self.normal_mode == "smoothed":  # the nodal normals (mean of the two facets') interpolated
            a, b = xb[self.segments[:, 0]], xb[self.segments[:, 1]]
            facet = np.column_stack([a[:, 1] - b[:, 1], b[:, 0] - a[:, 0]])
            facet *= (np.sign(facet[:, 1]) / np.linalg.norm(facet, axis=1))[:, None]
            nodal = np.zeros((self.n2, 2))
            for end in range(2):
                np.add.at(nodal, self.segments[:, end], facet)
            nodal /= np.maximum(np.linalg.norm(nodal, axis=1), 1e-300)[:, None]
            normal = weights[:, :1] * nodal[k[:, 0]] + weights[:, 1:] * nodal[k[:, 1]]
            normal /= np.linalg.norm(normal, axis=1)[:, None]
        tangent = np.column_stack([normal[:, 1], -normal[:, 0]])
        return Pairing(seg, k, weights, normal, tangent)

    def rows(self, pairing: Pairing) -> tuple[sp.csr_matrix, sp.csr_matrix, np.ndarray]:
        """B_n, B_t (nc x N) and g0 with g = g0 + B_n u, s = B_t u (module doc)."""
        i = np.arange(self.nc)
        cols, rows_n, vals_n, vals_t = [], [], [], []
        for comp in range(2):
            cols.append(2 * self.nodes + comp)
            rows_n.append(i)
            vals_n.append(pairing.normal[:, comp])
            vals_t.append(pairing.tangent[:, comp])
            for k in range(2):
                cols.append(2 * self.n1 + 2 * pairing.nodes[:, k] + comp)
                rows_n.append(i)
                vals_n.append(-pairing.weights[:, k] * pairing.normal[:, comp])
                vals_t.append(-pairing.weights[:, k] * pairing.tangent[:, comp])
        cols, rows_n = np.concatenate(cols), np.concatenate(rows_n)
        Bn = sp.csr_matrix((np.concatenate(vals_n), (rows_n, cols)), shape=(self.nc, self.N))
        Bt = sp.csr_matrix((np.concatenate(vals_t), (rows_n, cols)), shape=(self.nc, self.N))
        q = (pairing.weights[:, :1] * self.block.x[pairing.nodes[:, 0], :2]
             + pairing.weights[:, 1:] * self.block.x[pairing.nodes[:, 1], :2])
        g0 = ((self.X - q) * pairing.normal).sum(axis=1)
        return Bn, Bt, g0

    # -- the solver ------------------------------------------------------

    def prescribed_values(self, ux: float, uy: float) -> np.ndarray:
        values = np.zeros(self.N)
        values[2 * self.top] = ux
        values[2 * self.top + 1] = uy
        return values

    def initial_state(self) -> StepState:
        g0 = self.rows(self.reference_pairing)[2]
        state = np.where(g0 <= 1e-14, 1, 0)
        zero = np.zeros(self.nc)
        return StepState(np.zeros(self.N), zero.copy(), zero.copy(), state, np.zeros(self.nc))

    def _system(self, Bn, Bt, g0, state, direction, values, u_old):
        """The saddle-point system of one partition; unknowns (u, lambda_n, lambda_t)."""
        nc, mu, s = self.nc, self.mu, self.e_star
        free = ~self.prescribed
        F = sp.diags(free.astype(float))
        P = sp.diags(self.prescribed.astype(float))
        top = sp.hstack([F @ self.K + P, -(F @ Bn.T), -(F @ Bt.T)])
        contact = (state > 0).astype(float)
        stick = (state == 1).astype(float)
        slip = (state == 2).astype(float)
        opened = (state == 0).astype(float)
        normal = sp.hstack([s * sp.diags(contact) @ Bn, sp.diags(opened), sp.csr_matrix((nc, nc))])
        tangential = sp.hstack([s * sp.diags(stick) @ Bt, sp.diags(-mu * slip * direction),
                                sp.diags(slip + opened)])
        A = sp.vstack([top, normal, tangential]).tocsc()
        rhs = np.concatenate([np.where(self.prescribed, values, 0.0), -s * contact * g0,
                              s * stick * (Bt @ u_old)])
        return A, rhs

    def _update(self, lam_n, lam_t, g, v, state, direction):
        """The next partition (module doc) and the largest violation per node (for single switches)."""
        scale = max(np.abs(lam_n).max(), 1e-300)
        sigma = lam_n - self.c * g
        contact = sigma > 1e-12 * scale
        xi = lam_t - self.c * v
        bound = self.mu * np.maximum(sigma, 0.0)
        slack = CONE_SLACK * self.mu * scale
        stick = np.where(state == 2, np.abs(xi) < bound - slack, np.abs(xi) <= bound + slack)
        new_state = np.where(contact, np.where(stick, 1, 2), 0)
        new_direction = np.where(new_state == 2, np.sign(xi), 0.0)
        violation = np.abs(sigma) + np.abs(np.abs(xi) - bound)
        return new_state, new_direction, violation

    def _pdas(self, Bn, Bt, g0, start: StepState, values, u_old, history: list):
        """Primal-dual active set iterations on fixed rows; returns (u, lam_n, lam_t, state, direction)."""
        state, direction = start.state.copy(), start.direction.copy()
        seen = set()
        single = False
        for iteration in range(1, MAX_ITERATIONS + 1):
            A, rhs = self._system(Bn, Bt, g0, state, direction, values, u_old)
            z = spl.splu(A).solve(rhs)
            residual = np.linalg.norm(A @ z - rhs) / max(np.linalg.norm(rhs), 1e-300)
            if not residual < 1e-9:
                raise ReferenceFailure(f"the saddle-point solve failed (relative residual {residual:.2e})")
            u, lam_n, lam_t = z[: self.N], z[self.N: self.N + self.nc], z[self.N + self.nc:]
            g = g0 + Bn @ u
            v = Bt @ (u - u_old)
            new_state, new_direction, violation = self._update(lam_n, lam_t, g, v, state, direction)
            changed = (new_state != state) | ((new_state == 2) & (new_direction != direction))
            history.append({"contact": int((state > 0).sum()), "stick": int((state == 1).sum()),
                            "slip": int((state == 2).sum()), "changed": int(changed.sum())})
            if not changed.any():
                return u, lam_n, lam_t, state, direction
            key = (tuple(state), tuple(direction))
            if key in seen:
                single = True
            seen.add(key)
            if single:  # cycling: change only the node with the largest violation
                worst = np.flatnonzero(changed)[np.argmax(violation[changed])]
                one_state, one_direction = state.copy(), direction.copy()
                one_state[worst], one_direction[worst] = new_state[worst], new_direction[worst]
                new_state, new_direction = one_state, one_direction
            state, direction = new_state, new_direction
        raise ReferenceFailure(f"the active-set iteration did not settle in {MAX_ITERATIONS} iterations")

    def solve_step(self, start: StepState, ux: float, uy: float) -> tuple[StepState, dict]:
        """One load step from ``start`` (the last step's end): disc_top displaced by (ux, uy)."""
        begin = time.perf_counter()
        values = self.prescribed_values(ux, uy)
        u_old = start.u
        history: list = []
        pairing = self.reference_pairing
        current = start
        scale = max(abs(ux), abs(uy), 1e-300)
        # deformed pairing: a fixed point on the displacements the pairing is taken from, relaxed
        # by Aitken's factor (the plain iteration swings with period two on frictionless nodes)
        u_pair, r_prev, omega, change = u_old, None, 1.0, math.inf
        outer = 0
        for outer in range(1, MAX_OUTER + 1):
            if self.normal_mode != "reference":
                pairing = self._pair_deformed(u_pair)
            Bn, Bt, g0 = self.rows(pairing)
            u, lam_n, lam_t, state, direction = self._pdas(Bn, Bt, g0, current, values, u_old, history)
            current = StepState(u, lam_n, lam_t, state, direction)
            if self.normal_mode == "reference":
                break
            r = np.zeros(self.N)
            r[self.pair_dofs] = (u - u_pair)[self.pair_dofs]  # the dofs the pairing reads
            change = float(np.abs(r).max())
            if change <= 1e-10 * scale:
                break
            if r_prev is not None:
                dr = r - r_prev
                omega = float(np.clip(-omega * (r_prev @ dr) / max(dr @ dr, 1e-300), 0.05, 1.0))
            u_pair, r_prev = u_pair + omega * r, r
        else:
            raise ReferenceFailure(f"the deformed pairing did not settle in {MAX_OUTER} passes (change {change:.2e})")
        record = self._record(current, pairing, Bn, Bt, g0, u_old, values, ux, uy)
        if self.normal_mode != "reference":
            # the answer's own closest points give the same gaps as the rows it was solved with (a
            # node at a block vertex may pick the other segment there: same gap, other normal)
            fresh = self.rows(self._pair_deformed(current.u))
            gap = np.abs((fresh[2] + fresh[0] @ current.u) - (g0 + Bn @ current.u)) / self.h
            record["kkt"]["pairing"] = float(gap.max())
            record["kkt"]["passed"] = bool(record["kkt"]["passed"] and gap.max() <= KKT_TOLERANCE)
        record |= {"iterations": len(history), "outer_passes": outer, "history": history,
                   "seconds": time.perf_counter() - begin}
        return current, record

    # -- the answer --------------------------------------------------------

    def kkt(self, s: StepState, Bn, Bt, g0, u_old) -> dict:
        """The discrete KKT conditions of the module doc, relative figures."""
        lam_n, lam_t = s.lambda_n, s.lambda_t
        scale = max(lam_n.max(), 1e-300)
        h = self.h
        g = g0 + Bn @ s.u
        v = Bt @ (s.u - u_old)
        residual = self.K @ s.u - Bn.T @ lam_n - Bt.T @ lam_t
        loaded = lam_n > 1e-9 * scale
        inside = loaded & (np.abs(lam_t) < self.mu * lam_n * (1 - 1e-6))
        edge = loaded & ~inside
        figures = {
            "equilibrium": float(np.abs(residual[~self.prescribed]).max() / scale),
            "penetration": float(max(0.0, (-g / h).max())),
            "tension": float(max(0.0, -lam_n.min()) / scale),
            "complementarity": float((np.abs(lam_n * g) / h).max() / scale),
            "cone": float(max(0.0, (np.abs(lam_t) - self.mu * lam_n).max()) / (self.mu * scale)),
            "stick": float((np.abs(v[inside]) / h[inside]).max()) if inside.any() else 0.0,
            "slip": float(max(0.0, (lam_t[edge] * v[edge] / h[edge]).max()) / scale) if edge.any() else 0.0,
        }
        figures["passed"] = bool(max(figures.values()) <= KKT_TOLERANCE)
        return figures

    def uncovered(self, u: np.ndarray) -> float:
        """The deepest penetration of a disc contact node outside the candidates, over its spacing
        (deformed surfaces): must be 0."""
        if len(self.others) == 0:
            return 0.0
        xd, xb = self.positions(u)
        order = np.unique(self.segments)
        order = order[np.argsort(xb[order, 0])]
        below = np.interp(xd[self.others, 0], xb[order, 0], xb[order, 1]) - xd[self.others, 1]
        return float(max(0.0, below.max()))

    def _record(self, s: StepState, pairing: Pairing, Bn, Bt, g0, u_old, values, ux, uy) -> dict:
        g = g0 + Bn @ s.u
        v = Bt @ (s.u - u_old)
        force = s.lambda_n[:, None] * pairing.normal + s.lambda_t[:, None] * pairing.tangent  # on the disc
        reaction = self.K @ s.u
        top_force = reaction[self.top_dofs].reshape(2, -1).sum(axis=1)  # (x, y) the support passes to the disc
        kkt = self.kkt(s, Bn, Bt, g0, u_old)
        kkt["uncovered"] = self.uncovered(s.u)
        kkt["passed"] = bool(kkt["passed"] and kkt["uncovered"] == 0.0)
        xd, _ = self.positions(s.u)
        # P and Q as Johnson's (and internodes' summaries) define them: the total contact force
        # on the disc split along the zone's mean normal, the disc's own inward normals (of the
        # circle, centre R above its pole) weighted by the nodes' normal forces. Node by node
        # the split along the pairing's normal depends on which facet a node on a block vertex
        # is paired with (its normal turns by the kink, h / 2R); this split does not.
        total = force.sum(axis=0)
        centre = np.array([0.0, float(self.X[:, 1].min()) + RADIUS])
        inward = centre[None, :] - self.X[:, :2]
        inward /= np.linalg.norm(inward, axis=1)[:, None]
        pushing = (s.lambda_n[:, None] * inward).sum(axis=0)
        length = float(np.linalg.norm(pushing))
        m = pushing / length if length > 0.0 else np.array([0.0, 1.0])
        p_total = float(total @ m)
        return {
            "ux": ux, "uy": uy, "P": p_total, "Q": float((total - p_total * m)[0]),
            "tangential_force": (total - p_total * m).tolist(),
            "P_nodes": float(s.lambda_n.sum()), "Q_nodes": float(s.lambda_t.sum()),
            "force_on_disc": force.sum(axis=0).tolist(), "top_reaction": top_force.tolist(),
            "stick_nodes": int((s.state == 1).sum()), "slip_nodes": int((s.state == 2).sum()),
            "kkt": kkt,
            "nodes": {
                "tag": self.disc.node_tags[self.nodes].astype(int).tolist(),
                "x": self.X[:, 0].tolist(), "y": self.X[:, 1].tolist(),
                "x_deformed": xd[self.nodes, 0].tolist(),
                "area": self.area.tolist(), "h": self.h.tolist(),
                "state": s.state.astype(int).tolist(),
                "p": (s.lambda_n / self.area).tolist(), "q": (s.lambda_t / self.area).tolist(),
                "traction_x": (force[:, 0] / self.area).tolist(), "traction_y": (force[:, 1] / self.area).tolist(),
                "gap": g.tolist(), "slip": v.tolist(),
            },
        }

    def solve_path(self, steps: list[tuple[float, float]]) -> list[dict]:
        """Every step of the path in turn, each from the last one's end (module doc)."""
        state = self.initial_state()
        records = []
        for ux, uy in steps:
            state, record = self.solve_step(state, ux, uy)
            records.append(record)
        return records


# ---------------------------------------------------------------------------
# Post-processing shared with friction_suite.py
# ---------------------------------------------------------------------------


def johnson(force: float, shear: float, e_star: float, mu: float, radius: float = RADIUS) -> dict:
    """Hertz's a, p0 for P and Cattaneo-Mindlin's stick half-width c for Q (module doc)."""
    hertz = hertz_theory.contact(force, radius, e_star, 2)
    ratio = abs(shear) / (mu * force)
    c = hertz["a"] * math.sqrt(max(0.0, 1.0 - ratio))
    return {"a": hertz["a"], "p0": hertz["p0"], "c": c, "ratio": ratio}


def johnson_q(x: np.ndarray, a: float, p0: float, c: float, mu: float) -> np.ndarray:
    """Johnson's q(x) (module doc), positive; zero outside |x| < a."""
    x = np.asarray(x, float)
    q = mu * p0 * np.sqrt(np.clip(1 - x**2 / a**2, 0.0, None))
    if c > 0:
        q = q - np.where(np.abs(x) < c, mu * p0 * (c / a) * np.sqrt(np.clip(1 - x**2 / c**2, 0.0, None)), 0.0)
    return q


def stick_zone(x: np.ndarray, state: np.ndarray) -> dict:
    """The stick zone along x from nodal states (0 open, 1 stick, 2 slip) of one surface's nodes:
    each end half-way between the outermost stick node and the next node beyond it (its resolution
    is half a spacing); c = half the distance between the two ends, centre their mean; ``islands``
    the number of separate runs of stick nodes (1 for one zone)."""
    order = np.argsort(x)
    x, state = np.asarray(x, float)[order], np.asarray(state)[order]
    stick = np.flatnonzero(state == 1)
    if len(stick) == 0:
        return {"c": 0.0, "centre": math.nan, "left": math.nan, "right": math.nan, "islands": 0,
                "h_left": math.nan, "h_right": math.nan}
    lo, hi = stick[0], stick[-1]
    left = (x[lo] + x[lo - 1]) / 2 if lo > 0 else x[lo]
    right = (x[hi] + x[hi + 1]) / 2 if hi + 1 < len(x) else x[hi]
    runs = 1 + int((np.diff(stick) > 1).sum())
    h_left = x[lo] - x[lo - 1] if lo > 0 else math.nan
    h_right = x[hi + 1] - x[hi] if hi + 1 < len(x) else math.nan
    return {"c": float((right - left) / 2), "centre": float((right + left) / 2), "left": float(left),
            "right": float(right), "islands": runs, "h_left": float(h_left), "h_right": float(h_right)}


# ---------------------------------------------------------------------------
# Self-validation against Johnson
# ---------------------------------------------------------------------------

VERIFY_SPACINGS = (0.025, 0.0125, 0.00625)
VERIFY_APPROACH = 0.02
VERIFY_SHEAR = (0.002, 0.004, 0.006)
VERIFY_MU = 0.3
VERIFY_MATERIAL = (1000.0, 0.3)


def mesh(h_c: float, folder: Path) -> Path:
    """geo/half_disc_on_block.geo at h_c (r_c = 0.2, h_far = 0.5), cached (``suite.mesh_geo``)."""
    from suite import mesh_geo

    parameters = {"h_c": h_c, "r_c": 0.2, "h_far": 0.5}
    name = "half_disc_on_block" + "".join(f"_{k}{v:g}" for k, v in parameters.items()) + ".msh"
    return mesh_geo("half_disc_on_block", 2, parameters, folder / name)


def path_steps(approach: float, shear: tuple) -> list[tuple[float, float]]:
    """Press by ``approach`` (one step, ux = 0), then shear by each of ``shear`` at that approach."""
    return [(0.0, -approach)] + [(float(s), -approach) for s in shear]


def compare_with_johnson(record: dict, e_star: float, mu: float) -> dict:
    """Figures of one shear step against Johnson (equal materials)."""
    n = record["nodes"]
    x, q, state = np.array(n["x"]), np.array(n["traction_x"]), np.array(n["state"])
    shear = record["tangential_force"][0]
    j = johnson(record["P"], shear, e_star, mu)
    zone = stick_zone(x, state)
    contact = state > 0
    qj = johnson_q(x, j["a"], j["p0"], j["c"], mu)
    sign = 1.0 if shear >= 0 else -1.0
    difference = np.abs(sign * q - qj)
    h = float(np.median(np.array(n["h"])[contact])) if contact.any() else math.nan
    return {"ratio": j["ratio"], "a": j["a"], "p0": j["p0"], "c_johnson": j["c"], "c": zone["c"],
            "centre": zone["centre"], "islands": zone["islands"], "h": h,
            "c_error_over_h": abs(zone["c"] - j["c"]) / h,
            "q_max_error": float(difference.max() / (mu * j["p0"])),
            "q_rms_error": float(np.sqrt((difference[contact] ** 2).mean()) / (mu * j["p0"])),
            "a_nodes": float(np.abs(x[contact]).max()) if contact.any() else 0.0,
            "a_over_h": float((np.abs(x[contact]).max() - j["a"]) / h) if contact.any() else math.nan,
            "p_max_over_p0": float(np.max(n["p"]) / j["p0"])}


def verify(output: Path, normals=("reference", "deformed")) -> dict:
    """The reference against Johnson at three spacings (module doc); writes JSON and a figure."""
    output.mkdir(parents=True, exist_ok=True)
    results = {}
    for normal in normals:
        for h_c in VERIFY_SPACINGS:
            msh = mesh(h_c, output / "meshes")
            ref = FrictionReference(msh, VERIFY_MATERIAL, VERIFY_MATERIAL, VERIFY_MU, normal)
            records = ref.solve_path(path_steps(VERIFY_APPROACH, VERIFY_SHEAR))
            rows = []
            for k, record in enumerate(records):
                row = {"step": k, "ux": record["ux"], "P": record["P"], "Q": record["tangential_force"][0],
                       "kkt": record["kkt"], "iterations": record["iterations"],
                       "stick": record["stick_nodes"], "slip": record["slip_nodes"]}
                if k > 0:
                    row |= compare_with_johnson(record, ref.e_star, VERIFY_MU)
                rows.append(row)
            results[f"{normal} h_c={h_c:g}"] = {"normal": normal, "h_c": h_c, "steps": rows, "records": records,
                                                "candidates": ref.nc, "dofs": ref.N}
            print(f"{normal:9s} h_c = {h_c:<7g} ({ref.N} dofs, {ref.nc} candidates)")
            for row in rows:
                kkt = row["kkt"]
                line = (f"  step {row['step']} ux {row['ux']:<6g} P {row['P']:.6g} Q {row['Q']:+.5g}  "
                        f"stick {row['stick']:3d} slip {row['slip']:3d}  its {row['iterations']:2d}  "
                        f"KKT {'ok' if kkt['passed'] else 'FAILED'} (worst "
                        f"{max(v for k2, v in kkt.items() if k2 != 'passed'):.1e})")
                if row["step"] > 0:
                    line += (f"  Q/muP {row['ratio']:.4f}  c {row['c']:.4f} Johnson {row['c_johnson']:.4f} "
                             f"({row['c_error_over_h']:.2f} h)  q max {row['q_max_error']:.3f} rms "
                             f"{row['q_rms_error']:.3f} mu p0  p_max / p0 {row['p_max_over_p0']:.4f}, "
                             f"outermost contact node - a {row['a_over_h']:+.2f} h")
                print(line, flush=True)
    slim = {k: {kk: vv for kk, vv in v.items() if kk != "records"} for k, v in results.items()}
    (output / "friction_reference_verify.json").write_text(json.dumps(slim, indent=1))
    plot_verify(results, output / "friction_reference_verify.png")
    return results


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_verify(results: dict, path: Path) -> None:
    """q / (mu p0) against x / a at each shear step: the reference (every spacing) and Johnson."""
    plt = _pyplot()
    normals = sorted({v["normal"] for v in results.values()}, reverse=True)
    steps = len(VERIFY_SHEAR)
    fig, axes = plt.subplots(len(normals), steps, figsize=(4.2 * steps, 3.6 * len(normals)), squeeze=False)
    for r, normal in enumerate(normals):
        for k in range(steps):
            ax = axes[r][k]
            for (label, v), marker in zip([(l, v) for l, v in results.items() if v["normal"] == normal], "os^"):
                record = v["records"][k + 1]
                j = johnson(record["P"], record["Q"], hertz_theory.contact_modulus([VERIFY_MATERIAL] * 2), VERIFY_MU)
                x = np.array(record["nodes"]["x"]) / j["a"]
                q = np.array(record["nodes"]["traction_x"]) / (VERIFY_MU * j["p0"]) * np.sign(record["Q"])
                keep = np.abs(x) <= 1.5
                ax.plot(x[keep], q[keep], marker, ms=3, mfc="none", label=f"reference h_c = {v['h_c']:g}")
                if marker == "o":
                    s = np.linspace(-1, 1, 801)
                    ax.plot(s, johnson_q(s * j["a"], j["a"], j["p0"], j["c"], VERIFY_MU) / (VERIFY_MU * j["p0"]),
                            "k-", lw=1, label="Johnson (Cattaneo-Mindlin)")
            ax.set_title(f"{normal} pairing, ux = {VERIFY_SHEAR[k]:g}")
            ax.set_xlabel("x / a")
            ax.set_ylabel("q / (mu p0)")
            ax.grid(alpha=0.3)
            if k == 0:
                ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    solve = sub.add_parser("solve", help="one mesh along the path")
    solve.add_argument("mesh", type=Path)
    solve.add_argument("--approach", type=float, default=VERIFY_APPROACH)
    solve.add_argument("--shear", type=float, nargs="+", default=list(VERIFY_SHEAR))
    solve.add_argument("--E1", type=float, default=1000.0)
    solve.add_argument("--nu1", type=float, default=0.3)
    solve.add_argument("--E2", type=float, default=1000.0)
    solve.add_argument("--nu2", type=float, default=0.3)
    solve.add_argument("--mu", type=float, default=VERIFY_MU)
    solve.add_argument("--normal", choices=NORMALS, default="reference")
    solve.add_argument("--output", type=Path, default=VALIDATION / "build" / "friction_reference")
    check = sub.add_parser("verify", help="the reference against Johnson at three spacings")
    check.add_argument("--output", type=Path, default=VALIDATION / "build" / "friction_reference")
    args = parser.parse_args(argv)
    if args.command == "verify":
        results = verify(args.output)
        ok = all(row["kkt"]["passed"] for v in results.values() for row in v["steps"])
        print(f"written {args.output / 'friction_reference_verify.json'} and .png; KKT {'all passed' if ok else 'FAILED'}")
        return 0 if ok else 1
    ref = FrictionReference(args.mesh, (args.E1, args.nu1), (args.E2, args.nu2), args.mu, args.normal)
    records = ref.solve_path(path_steps(args.approach, tuple(args.shear)))
    args.output.mkdir(parents=True, exist_ok=True)
    (args.output / "friction_reference.json").write_text(json.dumps(records, indent=1))
    for k, r in enumerate(records):
        print(f"step {k}: ux {r['ux']:g} uy {r['uy']:g}: P {r['P']:.6g} Q {r['Q']:+.6g} stick {r['stick_nodes']} "
              f"slip {r['slip_nodes']} its {r['iterations']} KKT " + ", ".join(
                  f"{k2} {v:.1e}" for k2, v in r["kkt"].items() if k2 != "passed"))
    return 0 if all(r["kkt"]["passed"] for r in records) else 1


if __name__ == "__main__":
    sys.exit(main())
