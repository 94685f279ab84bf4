"""dolfinx's elastic solve of the contact benchmark on several MPI ranks (``mpirun -n 2``).

The parallel variant of ``contact_benchmark.py``'s dolfinx worker (which dispatches here when
``MPI.COMM_WORLD.size > 1``): the same problem (both volumes of the two-body mesh in one dolfinx
mesh, the case's Dirichlet data, no contact coupling), the same forms (sigma(u) : eps(v) per body),
the same CG + GAMG (rtol ``CG_RTOL``, rigid-body near-null space) or MUMPS Cholesky, and the same
timed phases (assemble, assemble loads, setup, solve). What differs is what a parallel run needs:

* the mesh is read by rank 0 only (``gmsh.merge``) and distributed by
  ``dolfinx.io.gmshio.model_to_mesh`` (dolfinx's partitioner); the other ranks never hold it;
* the near-null space is built from each rank's owned DOFs and orthonormalized with global
  (PETSc) dot products;
* every phase ends with a barrier and is timed on rank 0;
* rank 0 writes the result, with the peak resident memory (``ru_maxrss``) and the CPU time of
  every rank, and their sums.
"""

from __future__ import annotations

import json
import resource
import time
import tomllib
from pathlib import Path

import numpy as np

COMPONENTS = ("ux", "uy", "uz")


def _groups_and_mesh(path: Path, comm):
    """(physical name -> (dim, tag), mesh, cell tags, facet tags): read on rank 0, distributed."""
    import gmsh
    from dolfinx.io import gmshio

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        groups = None
        if comm.rank == 0:
            gmsh.model.add("contact benchmark")
            gmsh.merge(str(path))
            groups = {gmsh.model.getPhysicalName(d, t): (d, t) for d, t in gmsh.model.getPhysicalGroups()}
        groups = comm.bcast(groups, root=0)
        mesh, cell_tags, facet_tags = gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=3)
    finally:
        gmsh.finalize()
    return groups, mesh, cell_tags, facet_tags


def _near_null_space(V, A):
    """The six rigid-body modes on the owned DOFs, orthonormalized (modified Gram-Schmidt, global dots)."""
    from petsc4py import PETSc

    comm = V.mesh.comm
    owned = V.dofmap.index_map.size_local
    x = V.tabulate_dof_coordinates()[:owned, :3]
    centre = comm.allreduce(x.sum(axis=0), op=_mpi_sum()) / max(comm.allreduce(owned, op=_mpi_sum()), 1)
    x = x - centre
    modes = []
    for i in range(3):
        mode = np.zeros((owned, 3))
        mode[:, i] = 1.0
        modes.append(mode)
    for i, j in ((0, 1), (1, 2), (2, 0)):
        mode = np.zeros((owned, 3))
        mode[:, i], mode[:, j] = -x[:, j], x[:, i]
        modes.append(mode)
    vectors = []
    for mode in modes:
        v = A.createVecLeft()
        v.array[:] = mode.ravel()
        for w in vectors:
            v.axpy(-v.dot(w), w)
        v.scale(1.0 / v.norm())
        vectors.append(v)
    return PETSc.NullSpace().create(vectors=vectors, comm=comm)


def _mpi_sum():
    from mpi4py import MPI

    return MPI.SUM


def worker(solver: str, case_path: Path, output: Path, cg_rtol: float) -> None:
    """One elastic solve of both bodies on MPI.COMM_WORLD; rank 0 writes ``output`` (JSON)."""
    import ufl
    from dolfinx import fem
    from dolfinx.fem import petsc
    from mpi4py import MPI
    from petsc4py import PETSc

    comm = MPI.COMM_WORLD
    timings = {}
    comm.Barrier()
    clock = time.perf_counter()

    def lap(phase: str) -> None:
        """Time since the previous lap (every rank done: barrier), stored under ``phase`` (rank 0's clock)."""
        nonlocal clock
        comm.Barrier()
        timings[phase] = time.perf_counter() - clock
        clock = time.perf_counter()

    data = tomllib.loads(case_path.read_text())
    groups, mesh, cell_tags, facet_tags = _groups_and_mesh(case_path.parent / data["mesh"], comm)
    mesh.topology.create_connectivity(2, 3)
    V = fem.VectorFunctionSpace(mesh, ("CG", 1))
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
    lap("mesh")

    def tag(name: str, dim: int) -> int:
        if name not in groups or groups[name][0] != dim:
            raise RuntimeError(f"{case_path}: no physical group {name!r} of dimension {dim}")
        return groups[name][1]

    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    a_form, L_form, bcs = None, None, []
    zero = fem.Constant(mesh, np.zeros(3))
    for body in data["body"]:
        if body.get("load") or body.get("body_force"):
            raise RuntimeError(f"{case_path}: the benchmark expects Dirichlet data only (body {body['name']})")
        E, nu = float(body["youngs_modulus"]), float(body["poisson_ratio"])
        lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
        e = eps(u)
        term = ufl.inner(2 * mu * e + lam * ufl.tr(e) * ufl.Identity(3), eps(v)) * dx(tag(body["name"], 3))
        load = ufl.inner(zero, v) * dx(tag(body["name"], 3))
        a_form = term if a_form is None else a_form + term
        L_form = load if L_form is None else L_form + load
        for d in body.get("dirichlet", []):
            values = [d.get(c) for c in COMPONENTS]
            if any(value is None for value in values):
                raise RuntimeError("the benchmark expects fully prescribed Dirichlet groups")
            facets = facet_tags.indices[facet_tags.values == tag(d["group"], 2)]
            dofs = fem.locate_dofs_topological(V, 2, facets)
            bcs.append(fem.dirichletbc(np.array(values, dtype=PETSc.ScalarType), dofs, V))
    a, L = fem.form(a_form), fem.form(L_form)
    lap("form compilation")

    A = petsc.assemble_matrix(a, bcs=bcs)
    A.assemble()
    lap("assemble")
    b = petsc.assemble_vector(L)
    petsc.apply_lifting(b, [a], [bcs])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    petsc.set_bc(b, bcs)
    lap("assemble loads")
    ksp = PETSc.KSP().create(comm)
    ksp.setOperators(A)
    if solver == "cg":
        A.setNearNullSpace(_near_null_space(V, A))
        ksp.setType("cg")
        ksp.setTolerances(rtol=cg_rtol, atol=0.0, max_it=10000)
        ksp.getPC().setType("gamg")
    else:
        A.setOption(PETSc.Mat.Option.SPD, True)
        ksp.setType("preonly")
        ksp.getPC().setType("cholesky")
        ksp.getPC().setFactorSolverType("mumps")
    ksp.setFromOptions()
    lap("solver creation")
    ksp.setUp()
    lap("setup")
    x = A.createVecRight()
    ksp.solve(b, x)
    lap("solve")
    reason = ksp.getConvergedReason()
    r = b.duplicate()
    A.mult(x, r)
    r.axpy(-1.0, b)
    residual, x_norm, b_norm = r.norm(), x.norm(), b.norm()
    usage = resource.getrusage(resource.RUSAGE_SELF)
    peaks = comm.gather(usage.ru_maxrss / 1024, root=0)
    cpus = comm.gather(usage.ru_utime + usage.ru_stime, root=0)
    owned = comm.gather(V.dofmap.index_map.size_local * 3, root=0)
    nnz = int(A.getInfo(PETSc.Mat.InfoType.GLOBAL_SUM)["nz_used"])  # collective: every rank
    if comm.rank == 0:
        output.write_text(json.dumps({
            "ranks": comm.size, "timings": timings, "assemble": timings["assemble"],
            "solver_total": timings["setup"] + timings["solve"],
            "elastic_total": timings["assemble"] + timings["setup"] + timings["solve"],
            "iterations": ksp.getIterationNumber(), "converged_reason": int(reason),
            "relative_residual": residual / b_norm, "solution_norm": x_norm,
            "matrix_nnz": nnz, "dofs": A.getSize()[0],
            "rank_dofs": owned, "rank_peak_mb": peaks, "rank_cpu": cpus,
            "peak_mb_sum": sum(peaks), "cpu_sum": sum(cpus)}, indent=2))
    if reason <= 0:
        raise RuntimeError(f"{solver}: KSP did not converge (reason {reason})")
