"""FEniCSx (dolfinx 0.5.2) reference solutions for the internodes validation.

Everything here is computed independently of the Rust code, from the same
gmsh ``.msh`` file and the same case TOML file:

* the stiffness matrix of each body, assembled on ``dx(body)`` with P1
  (Lagrange, degree 1) vector elements and isotropic linear elasticity

      a(u, v) = int_body sigma(u) : eps(v) dx,
      eps(u)  = (grad u + grad u^T) / 2,
      sigma   = 2 mu eps + lambda tr(eps) I,
      lambda  = E nu / ((1 + nu)(1 - 2 nu)),   mu = E / (2 (1 + nu)),

  (plane strain in 2D: the same formula on the 2x2 tensors, sigma_zz =
  lambda tr(eps));
* the scalar surface mass matrix of a facet group G,
  M[a, b] = int_G phi_a phi_b ds;
* the solution of one body with the Dirichlet data and loads of the case
  file, its P1 (cell-constant) strain and stress, and its reactions
  R_G = sum over the dofs constrained by G of (K u - f), with K and f
  assembled without boundary conditions.

Results are returned in the numbering of the internodes output: for a body
with nodes x_0 .. x_{n-1} (its rows of ``/mesh/geometry``), the local node
index a, the dof index dim * a + component.  The dolfinx mesh reorders the
nodes, so the map is built by matching coordinates, which are bit-identical
since both codes read the same file; it must be a bijection.
"""

from __future__ import annotations

import contextlib
import logging
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import gmsh
import numpy as np
import scipy.sparse as sp
import ufl
from dolfinx import fem
from dolfinx.fem import petsc
from dolfinx.io import gmshio
from mpi4py import MPI
from petsc4py import PETSc
from scipy.spatial import cKDTree

logging.disable(logging.INFO)  # silence the compiler chatter of the FFCx JIT (setuptools logs at INFO)

COMPONENTS = ("ux", "uy", "uz")
# Coordinates are read from the same file by both codes: they must match exactly.
COORDINATE_TOLERANCE = 1e-13
# Tolerance of the reference's own sanity checks (relative to the data scale).
SELF_CHECK_TOLERANCE = 1e-11


class ReferenceFailure(RuntimeError):
    """The reference could not be built for this mesh / case (a clear message)."""


# ---------------------------------------------------------------------------
# Case file
# ---------------------------------------------------------------------------


@dataclass
class Dirichlet:
    """Prescribed displacement components on a boundary group (None = free)."""

    group: str
    values: tuple[float | None, ...]


@dataclass
class Load:
    """Boundary load on a group: exactly one of traction / pressure / hertz."""

    group: str
    traction: tuple[float, ...] | None = None
    pressure: float | None = None
    hertz: dict | None = None  # {"p0": float, "a": float, "center": [x, y(, z)]}


@dataclass
class Body:
    """One elastic body of the case file."""

    name: str
    youngs_modulus: float
    poisson_ratio: float
    body_force: tuple[float, ...] | None = None
    dirichlet: list[Dirichlet] = field(default_factory=list)
    loads: list[Load] = field(default_factory=list)

    def lame(self) -> tuple[float, float]:
        """(lambda, mu) from (E, nu)."""
        e, nu = self.youngs_modulus, self.poisson_ratio
        return e * nu / ((1 + nu) * (1 - 2 * nu)), e / (2 * (1 + nu))

    def boundary_groups(self) -> list[str]:
        """Every boundary group named for this body (Dirichlet first), no repeats."""
        names = [d.group for d in self.dirichlet] + [l.group for l in self.loads]
        return list(dict.fromkeys(names))


@dataclass
class Case:
    """A parsed case file (paths resolved against the case file's folder)."""

    path: Path
    mesh: Path
    bodies: list[Body]


def _take(table: dict, allowed: set[str], required: set[str], where: str) -> dict:
    """Check the keys of a TOML table: unknown or missing keys are errors."""
    unknown = set(table) - allowed
    missing = required - set(table)
    if unknown or missing:
        raise ReferenceFailure(f"{where}: unknown keys {sorted(unknown)}, missing keys {sorted(missing)}")
    return table


def read_case(path: str | Path) -> Case:
    """Parse a case TOML file (same format and strictness as the Rust reader)."""
    path = Path(path).resolve()
    with open(path, "rb") as f:
        data = tomllib.load(f)
    _take(data, {"mesh", "output", "body"}, {"mesh", "body"}, str(path))
    bodies = []
    for b in data["body"]:
        where = f"{path}: body {b.get('name', '?')}"
        _take(b, {"name", "youngs_modulus", "poisson_ratio", "body_force", "dirichlet", "load"},
              {"name", "youngs_modulus", "poisson_ratio"}, where)
        dirichlet = []
        for d in b.get("dirichlet", []):
            _take(d, {"group", *COMPONENTS}, {"group"}, f"{where}: dirichlet")
            dirichlet.append(Dirichlet(d["group"], tuple(d.get(c) for c in COMPONENTS)))
        loads = []
        for l in b.get("load", []):
            kinds = {"traction", "pressure", "hertz_pressure"}
            _take(l, {"group"} | kinds, {"group"}, f"{where}: load")
            if len(kinds & set(l)) != 1:
                raise ReferenceFailure(f"{where}: load on {l['group']} needs exactly one of {sorted(kinds)}")
            if "hertz_pressure" in l:
                _take(l["hertz_pressure"], {"p0", "a", "center"}, {"p0", "a", "center"}, f"{where}: hertz_pressure")
            loads.append(Load(l["group"], l.get("traction"), l.get("pressure"), l.get("hertz_pressure")))
        bodies.append(Body(b["name"], float(b["youngs_modulus"]), float(b["poisson_ratio"]),
                           b.get("body_force"), dirichlet, loads))
    return Case(path, (path.parent / data["mesh"]).resolve(), bodies)


# ---------------------------------------------------------------------------
# Numbering: dolfinx dofs <-> (body, local node) of the internodes output
# ---------------------------------------------------------------------------


def match_points(ours: np.ndarray, theirs: np.ndarray, where: str) -> np.ndarray:
    """Permutation p with theirs[p[a]] == ours[a] (exact coordinates).

    Fails unless both sets have the same size, every point of ``ours`` has
    a point of ``theirs`` at distance <= COORDINATE_TOLERANCE * diameter and
    the map is one-to-one.
    """
    if len(ours) != len(theirs):
        raise ReferenceFailure(f"{where}: {len(ours)} nodes in the internodes output, {len(theirs)} in dolfinx")
    scale = max(np.ptp(theirs, axis=0).max(), 1.0)
    dist, perm = cKDTree(theirs).query(ours)
    if dist.max() > COORDINATE_TOLERANCE * scale:
        a = int(dist.argmax())
        raise ReferenceFailure(f"{where}: node {a} at {ours[a]} has no dolfinx node (nearest at distance {dist[a]:.3e})")
    if len(np.unique(perm)) != len(perm):
        raise ReferenceFailure(f"{where}: coordinate map is not one-to-one (duplicate node coordinates?)")
    return perm


def restrict(matrix: sp.spmatrix, index: np.ndarray, where: str) -> sp.csr_matrix:
    """matrix[index][:, index], failing if ``matrix`` has nonzeros outside ``index``."""
    matrix = sp.csr_matrix(matrix)
    sub = matrix[index][:, index].tocsr()
    lost = abs(matrix).sum() - abs(sub).sum()
    if lost > SELF_CHECK_TOLERANCE * abs(matrix).sum():
        raise ReferenceFailure(f"{where}: the dolfinx matrix has entries outside this body's nodes")
    return sub


def to_scipy(matrix: PETSc.Mat) -> sp.csr_matrix:
    """A PETSc AIJ matrix as a scipy CSR matrix (all stored entries kept)."""
    indptr, indices, data = matrix.getValuesCSR()
    return sp.csr_matrix((data, indices, indptr), shape=matrix.getSize())


# ---------------------------------------------------------------------------
# The dolfinx model of a gmsh mesh
# ---------------------------------------------------------------------------


@dataclass
class BodySolution:
    """Reference solution of one body, in the internodes local numbering."""

    displacement: np.ndarray  # (num_nodes, dim)
    cells: np.ndarray  # (num_cells, dim + 1) local node indices
    strain: np.ndarray  # (num_cells, 9) full 3x3 tensor, row-major
    stress: np.ndarray  # (num_cells, 9)
    reactions: dict[str, np.ndarray]  # Dirichlet group -> (dim,)


class ReferenceModel:
    """A gmsh mesh loaded into dolfinx, with its physical groups.

    ``node_coordinates[body]`` must give the coordinates (num_nodes, 3) of
    the body's nodes in the internodes order; it defines the numbering of
    every result.
    """

    def __init__(self, msh_path: str | Path, node_coordinates: dict[str, np.ndarray]):
        self.path = Path(msh_path)
        if not self.path.is_file():
            raise ReferenceFailure(f"mesh file {self.path} does not exist")
        with _gmsh_model(self.path):
            self.dim = gmsh.model.getDimension()
            self.groups = {gmsh.model.getPhysicalName(d, t): (d, t) for d, t in gmsh.model.getPhysicalGroups()}
            self.group_sizes = _gmsh_boundary_groups(self.groups, self.dim - 1)
            self.node_positions = _gmsh_node_positions()
            self.body_elements = {name: _gmsh_elements(d, t) for name, (d, t) in self.groups.items() if d == self.dim}
            self.mesh, self.cell_tags, self.facet_tags = gmshio.model_to_mesh(
                gmsh.model, MPI.COMM_WORLD, 0, gdim=self.dim)
        self.mesh.topology.create_connectivity(self.dim - 1, self.dim)
        self.V = fem.VectorFunctionSpace(self.mesh, ("CG", 1))
        self.Q = fem.FunctionSpace(self.mesh, ("CG", 1))
        self.W = fem.VectorFunctionSpace(self.mesh, ("DG", 0), dim=9)  # 3x3 tensors per cell
        self.dx = ufl.Measure("dx", domain=self.mesh, subdomain_data=self.cell_tags)
        self.ds = ufl.Measure("ds", domain=self.mesh, subdomain_data=self.facet_tags)
        self.node_coordinates = node_coordinates
        self._vertex_maps: dict[str, np.ndarray] = {}

    # -- groups -----------------------------------------------------------

    def group_measure(self, group: str) -> float:
        """Length (2D) or area (3D) of a boundary group, computed from gmsh's elements."""
        self.group_tag(group, self.dim - 1)
        return self.group_sizes[group][1]

    def group_tag(self, name: str, dim: int) -> int:
        """Physical tag of group ``name`` of dimension ``dim`` (clear error otherwise)."""
        if name not in self.groups or self.groups[name][0] != dim:
            raise ReferenceFailure(f"{self.path}: no physical group '{name}' of dimension {dim} "
                                   f"(groups: {sorted(self.groups)})")
        return self.groups[name][1]

    def facets(self, group: str) -> np.ndarray:
        """dolfinx facets of a boundary group (checked against gmsh's element count)."""
        tag = self.group_tag(group, self.dim - 1)
        facets = self.facet_tags.indices[self.facet_tags.values == tag]
        expected = self.group_sizes[group][0]
        if len(facets) != expected:
            raise ReferenceFailure(f"{self.path}: group '{group}' has {expected} gmsh elements "
                                   f"but {len(facets)} tagged dolfinx facets")
        return facets

    def body_cells(self, body: str) -> np.ndarray:
        """dolfinx cells of a body."""
        tag = self.group_tag(body, self.dim)
        return self.cell_tags.indices[self.cell_tags.values == tag]

    # -- numbering --------------------------------------------------------

    def vertex_map(self, body: str) -> np.ndarray:
        """dolfinx P1 dof (vertex) of each internodes local node of ``body``.

        V (vector, block size dim) and Q (scalar) share the same vertex
        dofmap in serial; both are checked.
        """
        if body not in self._vertex_maps:
            if body not in self.node_coordinates:
                raise ReferenceFailure(f"no internodes node coordinates for body '{body}'")
            cell_dofs = self.V.dofmap.list.array.reshape(-1, self.dim + 1)
            if not np.array_equal(cell_dofs, self.Q.dofmap.list.array.reshape(-1, self.dim + 1)):
                raise ReferenceFailure("dolfinx: scalar and vector P1 dofmaps differ")
            dofs = np.unique(cell_dofs[self.body_cells(body)])
            coords = self.V.tabulate_dof_coordinates()[dofs]
            perm = match_points(self.node_coordinates[body], coords, f"{self.path}: body '{body}'")
            self._vertex_maps[body] = dofs[perm]
        return self._vertex_maps[body]

    def dof_map(self, body: str) -> np.ndarray:
        """dolfinx vector dof of each internodes dof dim * a + i of ``body``."""
        return (self.dim * self.vertex_map(body)[:, None] + np.arange(self.dim)).ravel()

    def local_cells(self, body: str) -> np.ndarray:
        """Cells of ``body`` as internodes local node indices (num_cells, dim + 1)."""
        local = np.full(self.V.dofmap.index_map.size_local, -1)
        local[self.vertex_map(body)] = np.arange(len(self.vertex_map(body)))
        cell_dofs = self.V.dofmap.list.array.reshape(-1, self.dim + 1)
        return local[cell_dofs[self.body_cells(body)]]

    # -- forms ------------------------------------------------------------

    def _strain3(self, u) -> ufl.core.expr.Expr:
        """eps(u) as a 3x3 tensor (zero third row / column in 2D)."""
        e = ufl.sym(ufl.grad(u))
        return ufl.as_matrix([[e[i, j] if i < self.dim and j < self.dim else 0.0 for j in range(3)]
                              for i in range(3)])

    def _stress3(self, u, body: Body) -> ufl.core.expr.Expr:
        """sigma(u) = 2 mu eps + lambda tr(eps) I as a 3x3 tensor (plane strain in 2D)."""
        lam, mu = body.lame()
        e = self._strain3(u)
        return 2 * mu * e + lam * ufl.tr(e) * ufl.Identity(3)

    def stiffness_form(self, body: Body) -> ufl.Form:
        """a(u, v) = int_body sigma(u) : eps(v) dx."""
        u, v = ufl.TrialFunction(self.V), ufl.TestFunction(self.V)
        tag = self.group_tag(body.name, self.dim)
        return ufl.inner(self._stress3(u, body), self._strain3(v)) * self.dx(tag)

    def load_form(self, body: Body) -> ufl.Form:
        """L(v) = int_body b.v dx + sum over loads int_G t.v ds.

        Traction t: constant vector, -p n (pressure) or -p_h n with p_h the
        P1 interpolant of the Hertz pressure p0 sqrt(max(0, 1 - r^2/a^2)).
        All integrands are polynomials of degree <= 2 on flat facets, so a
        degree-2 quadrature integrates them exactly.
        """
        v = ufl.TestFunction(self.V)
        n = ufl.FacetNormal(self.mesh)
        zero = fem.Constant(self.mesh, np.zeros(self.dim))
        tag = self.group_tag(body.name, self.dim)
        form = ufl.inner(zero, v) * self.dx(tag)  # a valid form even for an unloaded body
        if body.body_force is not None:
            form += ufl.inner(self._constant(body.body_force, f"body force of {body.name}"), v) * self.dx(tag)
        for load in body.loads:
            ds = self.ds(self.group_tag(load.group, self.dim - 1), metadata={"quadrature_degree": 2})
            if load.traction is not None:
                t = self._constant(load.traction, f"traction on {load.group}")
            elif load.pressure is not None:
                t = -float(load.pressure) * n
            else:
                t = -self._hertz_pressure(load.hertz) * n
            form += ufl.inner(t, v) * ds
        return form

    def _constant(self, values, what: str) -> fem.Constant:
        """A constant vector of length dim."""
        if len(values) != self.dim:
            raise ReferenceFailure(f"{what}: expected {self.dim} components, got {list(values)}")
        return fem.Constant(self.mesh, np.asarray(values, dtype=float))

    def _hertz_pressure(self, hertz: dict) -> fem.Function:
        """P1 interpolant of p(x) = p0 sqrt(max(0, 1 - |x - c|^2 / a^2))."""
        p0, a = float(hertz["p0"]), float(hertz["a"])
        center = np.zeros(3)
        center[: len(hertz["center"])] = hertz["center"]
        p = fem.Function(self.Q)
        p.interpolate(lambda x: p0 * np.sqrt(np.maximum(0.0, 1.0 - ((x.T - center) ** 2).sum(axis=1) / a**2)))
        return p

    # -- matrices in the internodes numbering ----------------------------

    def stiffness(self, body: Body) -> sp.csr_matrix:
        """Unconstrained stiffness of ``body`` in the internodes dof numbering."""
        K = petsc.assemble_matrix(fem.form(self.stiffness_form(body)))
        K.assemble()
        K = restrict(to_scipy(K), self.dof_map(body.name), f"{self.path}: stiffness of '{body.name}'")
        self._check_rigid_modes(K, body.name)
        return K

    def surface_mass(self, body: str, group: str) -> sp.csr_matrix:
        """M[a, b] = int_G phi_a phi_b ds in the internodes local node numbering of ``body``."""
        self.facets(group)  # the group exists and is fully tagged
        p, q = ufl.TrialFunction(self.Q), ufl.TestFunction(self.Q)
        ds = self.ds(self.group_tag(group, self.dim - 1), metadata={"quadrature_degree": 2})
        M = petsc.assemble_matrix(fem.form(p * q * ds))
        M.assemble()
        M = restrict(to_scipy(M), self.vertex_map(body), f"{self.path}: mass of '{group}' on '{body}'")
        measure = self.group_measure(group)
        if abs(M.sum() - measure) > SELF_CHECK_TOLERANCE * measure:
            raise ReferenceFailure(f"{self.path}: dolfinx mass of '{group}' sums to {M.sum()}, "
                                   f"gmsh measure is {measure}")
        return M

    def _check_rigid_modes(self, K: sp.csr_matrix, body: str) -> None:
        """Self-check: K r = 0 for the rigid-body modes r of the body."""
        x = self.node_coordinates[body][:, : self.dim]
        modes = rigid_body_modes(x)
        residual = abs(K @ modes).max() / (abs(K).max() * abs(modes).max())
        if residual > SELF_CHECK_TOLERANCE:
            raise ReferenceFailure(f"{self.path}: dolfinx stiffness of '{body}' does not annihilate "
                                   f"rigid-body modes (relative residual {residual:.2e})")

    # -- solve ------------------------------------------------------------

    def load_vector(self, body: Body) -> np.ndarray:
        """f_a = L(phi_a) of ``body`` in the internodes dof numbering."""
        f = petsc.assemble_vector(fem.form(self.load_form(body)))
        f.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        local = f.array[self.dof_map(body.name)]
        if abs(abs(f.array).sum() - abs(local).sum()) > SELF_CHECK_TOLERANCE * abs(f.array).sum():
            raise ReferenceFailure(f"{self.path}: loads of '{body.name}' act on nodes of another body")
        return local

    def dirichlet_dofs(self, body: Body) -> dict[str, dict[int, np.ndarray]]:
        """For each Dirichlet group: component i -> the internodes dofs dim * a + i it constrains."""
        local = np.full(self.dim * self.V.dofmap.index_map.size_local, -1)
        local[self.dof_map(body.name)] = np.arange(self.dim * len(self.vertex_map(body.name)))
        result = {}
        for d in body.dirichlet:
            facets = self.facets(d.group)
            result[d.group] = {i: local[fem.locate_dofs_topological(self.V.sub(i), self.dim - 1, facets)]
                               for i, value in enumerate(d.values[: self.dim]) if value is not None}
            if any((dofs < 0).any() for dofs in result[d.group].values()):
                raise ReferenceFailure(f"{self.path}: Dirichlet group '{d.group}' is not on body '{body.name}'")
        return result

    def solve(self, body: Body, pinned: dict[int, float] | None = None) -> BodySolution:
        """Solve the body's problem; displacements, cell strains / stresses, reactions.

        With C the constrained dofs (values g) and F the free ones:
        u_C = g, K_FF u_F = f_F - K_FC g (Cholesky, MUMPS); then the reactions
        R_G[i] = sum over the dofs of component i constrained by G of
        (K u - f), K and f unconstrained (a free component gives 0). ``pinned``
        (internodes dof -> value) constrains more dofs, for a body its
        Dirichlet groups leave free to move; their reactions are under the
        group name ``"pinned"``.
        """
        K, f = self.stiffness(body), self.load_vector(body)
        constrained = self.dirichlet_dofs(body)
        g = prescribed_values(body, constrained, len(f))
        if pinned:
            g[list(pinned)] = list(pinned.values())
        u = solve_constrained(K, f, g, f"{self.path}: body '{body.name}'")
        residual = K @ u - f
        reactions = {group: np.array([residual[dofs[i]].sum() if i in dofs else 0.0 for i in range(self.dim)])
                     for group, dofs in constrained.items()}
        if pinned:
            dofs = np.array(sorted(pinned))
            reactions["pinned"] = np.array([residual[dofs[dofs % self.dim == i]].sum() for i in range(self.dim)])
        strain, stress = self._cell_tensors(u, body)
        return BodySolution(u.reshape(-1, self.dim), self.local_cells(body.name), strain, stress, reactions)

    def _cell_tensors(self, u: np.ndarray, body: Body) -> tuple[np.ndarray, np.ndarray]:
        """Per-cell strain and stress (3x3, row-major) of ``body`` for the
        displacement dofs u (internodes numbering).

        For P1 displacements grad u is constant per cell, so interpolating
        the UFL expressions into DG0 is exact (no projection).
        """
        uh = fem.Function(self.V)
        uh.x.array[self.dof_map(body.name)] = u
        cells = self.body_cells(body.name)
        result = []
        for tensor in (self._strain3(uh), self._stress3(uh, body)):
            w = fem.Function(self.W)
            flat = ufl.as_vector([tensor[i, j] for i in range(3) for j in range(3)])
            w.interpolate(fem.Expression(flat, self.W.element.interpolation_points()), cells=cells)
            result.append(w.x.array.reshape(-1, 9)[self.W.dofmap.list.array[cells]])
        return result[0], result[1]


# ---------------------------------------------------------------------------
# Helpers (gmsh geometry, rigid modes)
# ---------------------------------------------------------------------------


def prescribed_values(body: Body, constrained: dict[str, dict[int, np.ndarray]], size: int) -> np.ndarray:
    """Vector of prescribed dof values, NaN where free; conflicting values are an error."""
    g = np.full(size, np.nan)
    for d in body.dirichlet:
        for i, dofs in constrained[d.group].items():
            if (np.abs(g[dofs] - d.values[i]) > 0).any():
                raise ReferenceFailure(f"body '{body.name}': group '{d.group}' prescribes {COMPONENTS[i]} = "
                                       f"{d.values[i]} on nodes where another group prescribes another value")
            g[dofs] = d.values[i]
    return g


def solve_constrained(K: sp.csr_matrix, f: np.ndarray, g: np.ndarray, where: str) -> np.ndarray:
    """u with u_C = g_C (C: dofs where g is not NaN) and K_FF u_F = f_F - K_FC g_C.

    K_FF is symmetric positive definite: Cholesky (MUMPS through PETSc);
    the residual is checked.
    """
    fixed = ~np.isnan(g)
    free = np.flatnonzero(~fixed)
    u = np.where(fixed, g, 0.0)
    A = K[free][:, free].tocsr()
    b = (f - K @ u)[free]
    mat = PETSc.Mat().createAIJ(A.shape, csr=(A.indptr, A.indices, A.data))
    mat.setOption(PETSc.Mat.Option.SPD, True)
    ksp = PETSc.KSP().create()
    ksp.setOperators(mat)
    ksp.setType("preonly")
    ksp.getPC().setType("cholesky")
    ksp.getPC().setFactorSolverType("mumps")
    x, rhs = mat.createVecs()
    rhs.array[:] = b
    ksp.solve(rhs, x)
    u[free] = x.array
    if np.linalg.norm(A @ u[free] - b) > SELF_CHECK_TOLERANCE * max(np.linalg.norm(b), 1e-300):
        raise ReferenceFailure(f"{where}: the linear solve failed (is the body fully constrained?)")
    return u


def rigid_body_modes(x: np.ndarray) -> np.ndarray:
    """Rigid-body modes (dim * n, 3 or 6) of nodes x (n, dim), interleaved dofs.

    Translations e_i and infinitesimal rotations w x (x - mean(x)).
    """
    n, dim = x.shape
    x = x - x.mean(axis=0)
    modes = [np.tile(np.eye(dim)[i], n) for i in range(dim)]
    rotations = [(0, 1)] if dim == 2 else [(0, 1), (1, 2), (2, 0)]
    for i, j in rotations:
        mode = np.zeros((n, dim))
        mode[:, i], mode[:, j] = -x[:, j], x[:, i]
        modes.append(mode.ravel())
    return np.column_stack(modes)


@contextlib.contextmanager
def _gmsh_model(path: Path):
    """The gmsh API with ``path`` opened as the current model."""
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        yield
    finally:
        gmsh.finalize()


def _gmsh_node_positions() -> np.ndarray:
    """Coordinates of the gmsh nodes of the current model, row = node tag (NaN: no such tag)."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    tags = tags.astype(np.int64)
    position = np.full((tags.max() + 1, 3), np.nan)
    position[tags] = coords.reshape(-1, 3)
    return position


def _gmsh_elements(dim: int, tag: int) -> tuple[np.ndarray, np.ndarray]:
    """(element tags (m,), node tags (m, dim + 1)) of physical group (dim, tag); linear simplices only."""
    element_tags, element_nodes = [np.zeros(0, np.int64)], [np.zeros((0, dim + 1), np.int64)]
    for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
        for etype, tags, nodes in zip(*gmsh.model.mesh.getElements(dim, entity)):
            if gmsh.model.mesh.getElementProperties(etype)[3] != dim + 1:
                raise ReferenceFailure(f"physical group {tag}: element type {etype} is not a linear simplex")
            element_tags.append(tags.astype(np.int64))
            element_nodes.append(nodes.astype(np.int64).reshape(-1, dim + 1))
    return np.concatenate(element_tags), np.concatenate(element_nodes)


def _gmsh_boundary_groups(groups: dict[str, tuple[int, int]], dim: int) -> dict[str, tuple[int, float]]:
    """(number of elements, length (dim 1) or area (dim 2)) of each physical
    group of dimension dim, from gmsh's elements (independent of dolfinx)."""
    position = _gmsh_node_positions()
    sizes = {}
    for name, (d, tag) in groups.items():
        if d == dim:
            x = position[_gmsh_elements(d, tag)[1]]
            edges = x[:, 1:] - x[:, :1]
            measure = (np.linalg.norm(edges[:, 0], axis=1).sum() if d == 1 else
                       0.5 * np.linalg.norm(np.cross(edges[:, 0], edges[:, 1]), axis=1).sum())
            sizes[name] = (len(x), measure)
    return sizes
