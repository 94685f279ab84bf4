"""Cases and meshes pickle (a case as its keys, re-checked; a mesh read from a file by its path,
a mesh gmsh made as its MSH bytes, a gmsh model's mesh as its arrays), so that a
ProcessPoolExecutor can solve them."""

import multiprocessing
import pickle
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

import internodes
from conftest import REPO

MSH = REPO / "tests" / "fixtures" / "half_disc_on_block.msh"
TOML = REPO / "geo" / "half_disc_on_block.toml"


def dict_case(approach):
    return internodes.Case.from_dict({
        "contact": {"bodies": ["disc", "block"], "surfaces": ["disc_contact", "block_contact"]},
        "body": [{"name": "disc", "youngs_modulus": 1e3, "poisson_ratio": 0.3,
                  "dirichlet": [{"group": "disc_top", "ux": 0.0, "uy": -approach}]},
                 {"name": "block", "youngs_modulus": 1e3, "poisson_ratio": 0.3,
                  "dirichlet": [{"group": "block_base", "ux": 0.0, "uy": 0.0}]}]},
        name=f"approach {approach}")


def force(case, mesh=None):
    """Runs in a worker process: the contact force of the solve (a Result does not pickle)."""
    return internodes.solve(case, mesh=mesh).summary["contact"]["force_primary"]


def round_trip(value):
    return pickle.loads(pickle.dumps(value))


def test_cases_and_meshes_survive_a_pickle():
    mesh = internodes.Mesh.from_msh(MSH)
    generated = internodes.Mesh.from_geo(REPO / "geo" / "half_disc_on_block.geo", {"level": 0})
    for case, mesh in [(internodes.Case.from_toml(TOML), None), (dict_case(0.02), mesh),
                       (dict_case(0.01), generated)]:
        again, mesh_again = round_trip(case), mesh and round_trip(mesh)
        assert repr(again) == repr(case) and again.mesh == case.mesh
        assert again.load_steps == case.load_steps
        if mesh is not None:
            assert repr(mesh_again) == repr(mesh) and mesh_again.groups == mesh.groups
        a, b = internodes.solve(case, mesh=mesh), internodes.solve(again, mesh=mesh_again)
        assert a.summary["contact"]["force_primary"] == b.summary["contact"]["force_primary"]
        assert np.array_equal(a.bodies["disc"].displacement, b.bodies["disc"].displacement)


def test_a_gmsh_model_mesh_pickles_as_its_arrays():
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Verbosity", 0)
        gmsh.open(str(REPO / "geo" / "half_disc_on_block.geo"))
        gmsh.model.mesh.generate(2)
        mesh = internodes.Mesh.from_gmsh()
    finally:
        gmsh.finalize()
    again = round_trip(mesh)
    assert repr(again) == repr(mesh) and again.groups == mesh.groups
    case = dict_case(0.02)
    assert force(case, mesh) == force(case, again)


def test_a_process_pool_solves_pickled_cases():
    mesh = internodes.Mesh.from_msh(MSH)
    cases = [dict_case(d) for d in (0.01, 0.02)]
    spawn = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=2, mp_context=spawn) as pool:
        forces = list(pool.map(force, cases, [mesh] * len(cases)))
    assert forces == [force(c, mesh) for c in cases]
