"""A mesh read from gmsh's current model equals the same model written to a file and read
back. The files are binary: gmsh's ASCII writer keeps 16 significant digits, which moves some
coordinates by an ulp, and the answers then differ at round-off."""

import importlib.util

import numpy as np
import pytest

import internodes
from conftest import REPO, comparable

gmsh = pytest.importorskip("gmsh")


def example(name):
    """A module of python/examples/, imported from its file."""
    spec = importlib.util.spec_from_file_location(name, REPO / "python" / "examples" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_model_and_its_file_give_one_mesh_and_one_answer(tmp_path):
    gmsh_in_memory = example("gmsh_in_memory")
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh_in_memory.build_half_disc_on_block(h_contact=0.04)
        in_memory = internodes.Mesh.from_gmsh()
        gmsh.option.setNumber("Mesh.Binary", 1)
        gmsh.write(str(tmp_path / "model.msh"))
    finally:
        gmsh.finalize()
    from_file = internodes.Mesh.from_msh(tmp_path / "model.msh")
    assert (in_memory.dim, in_memory.bodies) == (from_file.dim, from_file.bodies) == (2, ["disc", "block"])
    assert set(in_memory.groups) == set(from_file.groups)

    case = gmsh_in_memory.case()
    ours, theirs = internodes.solve(case, mesh=in_memory), internodes.solve(case, mesh=from_file)
    assert ours.status == "converged"
    assert comparable(ours.summary, ["mesh"]) == comparable(theirs.summary, ["mesh"])
    for name in ["disc", "block"]:
        a, b = ours.bodies[name], theirs.bodies[name]
        assert np.array_equal(a.node_tags, b.node_tags) and np.array_equal(a.cells, b.cells)
        assert np.array_equal(a.displacement, b.displacement)
        assert np.array_equal(a.surface.pressure, b.surface.pressure)


def test_a_3d_model_reads_its_volumes(tmp_path):
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("cube")
        gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [1]), "cube")
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, [5]), "bottom")
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, [6]), "top")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.4)
        gmsh.model.mesh.generate(3)
        mesh = internodes.Mesh.from_gmsh("cube")
        gmsh.option.setNumber("Mesh.Binary", 1)
        gmsh.write(str(tmp_path / "cube.msh"))
    finally:
        gmsh.finalize()
    assert (mesh.dim, mesh.bodies, str(mesh.path)) == (3, ["cube"], "gmsh model 'cube'")
    case = internodes.Case.from_dict({"body": [{
        "name": "cube", "youngs_modulus": 1.0, "poisson_ratio": 0.25,
        "dirichlet": [{"group": "bottom", "ux": 0.0, "uy": 0.0, "uz": 0.0},
                      {"group": "top", "uz": -0.01}]}]})
    ours = internodes.solve(case, mesh=mesh)
    theirs = internodes.solve(case, mesh=internodes.Mesh.from_msh(tmp_path / "cube.msh"))
    assert ours.status is None and ours.exit_code == 0
    assert np.array_equal(ours.bodies["cube"].displacement, theirs.bodies["cube"].displacement)
    # The reaction on the top balances the one on the bottom.
    reactions = ours.summary["bodies"][0]["reactions"]
    assert np.allclose(reactions["top"], -np.array(reactions["bottom"]), atol=1e-9)
