"""Every public object says what it is (`repr`), a mesh gives its sizes, the package its
version, and `Mesh.from_gmsh` before `gmsh.initialize()` says so."""

import subprocess
import sys

import internodes
from conftest import REPO

MSH = REPO / "tests" / "fixtures" / "half_disc_on_block.msh"


def test_the_version_is_the_solver_s():
    cargo = (REPO / "Cargo.toml").read_text()
    assert f'version = "{internodes.__version__}"' in cargo


def test_a_mesh_gives_its_sizes_per_body():
    mesh = internodes.Mesh.from_msh(MSH)
    assert mesh.num_nodes == {"disc": 402, "block": 490}
    assert mesh.num_cells == {"disc": 752, "block": 918}
    assert repr(mesh) == (f"Mesh('{MSH}', dim=2, bodies={{'disc': 402 nodes, 752 cells, "
                          "'block': 490 nodes, 918 cells})")


def test_every_public_object_has_a_repr():
    case = internodes.Case.from_toml(REPO / "geo" / "half_disc_on_block.toml")
    result = internodes.solve(case)
    body = result.bodies["disc"]
    objects = [case, internodes.Mesh.from_msh(MSH), result, body, body.surface, result.steps[0],
               internodes.Cancel()]
    for value in objects:
        text = repr(value)
        assert text.startswith(type(value).__name__ + "("), text
        assert " object at 0x" not in text, text
    assert repr(body.surface) == f"SurfaceResult({len(body.surface.nodes)} nodes, " \
                                 f"{int(body.surface.active.sum())} active)"


def test_from_gmsh_before_gmsh_is_initialized_says_so():
    # In a process of its own: gmsh's state is global.
    script = ("import internodes\n"
              "try:\n    internodes.Mesh.from_gmsh()\n"
              "except internodes.InputError as e:\n    print(e)\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("gmsh is not initialized: call gmsh.initialize()"), done.stdout
    assert "the file" not in done.stdout
