"""A result as meshio meshes, without files; and the summary's typed view describes real
summaries key for key."""

import typing

import numpy as np
import pytest

import internodes
from conftest import REPO
from internodes import summary as typed

meshio = pytest.importorskip("meshio")


@pytest.fixture(scope="module")
def half_disc():
    return internodes.solve(internodes.Case.from_toml(REPO / "geo" / "half_disc_on_block.toml"))


def test_a_result_is_one_meshio_mesh_per_body_with_its_fields(half_disc, tmp_path):
    meshes = internodes.to_meshio(half_disc)
    assert set(meshes) == {"disc", "block"}
    for name, body in half_disc.bodies.items():
        mesh = meshes[name]
        assert np.array_equal(mesh.points, body.coordinates)
        assert mesh.cells[0].type == "triangle"
        assert np.array_equal(mesh.cells[0].data, body.cells.astype(np.int64))
        assert np.array_equal(mesh.point_data["displacement"], body.displacement)
        assert np.array_equal(mesh.cell_data["von_mises"][0], body.von_mises)
        # Contact fields on the candidate surface, zero elsewhere.
        nodes = body.surface.nodes.astype(int)
        pressure = mesh.point_data["contact_pressure"]
        assert np.array_equal(pressure[nodes], body.surface.pressure)
        assert not np.delete(pressure, nodes).any()
        # Tensors as 9 components per cell, row by row.
        assert np.array_equal(mesh.cell_data["stress"][0], body.stress.reshape(-1, 9))
        assert np.array_equal(mesh.cell_data["strain"][0][:, [0, 4, 8]],
                              np.diagonal(body.strain, axis1=1, axis2=2))


@pytest.mark.parametrize("extension", ["xdmf", "vtu", "vtk"])
def test_every_field_survives_each_meshio_writer(half_disc, tmp_path, extension):
    # meshio 5.0.0's VTU writer kept one value of a (m, 3, 3) tensor per cell and its legacy VTK
    # writer wrote a file it could not read: every field is read back here, value for value.
    for name, mesh in internodes.to_meshio(half_disc).items():
        body = half_disc.bodies[name]
        path = tmp_path / f"{name}.{extension}"
        # meshio's legacy VTK writer pads the mesh's own 2D vectors to 3 components.
        written = {key: values.copy() for key, values in mesh.point_data.items()}
        meshio.write(path, mesh)
        again = meshio.read(path)
        for key in ["strain", "stress"]:
            values = again.cell_data[key][0]
            assert values.shape == (len(body.cells), 9), (key, values.shape)
            assert np.array_equal(values.reshape(-1, 3, 3), getattr(body, key)), key
        assert np.array_equal(again.cell_data["von_mises"][0], body.von_mises)
        dim = body.displacement.shape[1]
        # Legacy VTK pads 2D vectors to 3 components.
        assert np.array_equal(again.point_data["displacement"][:, :dim], body.displacement)
        for key in ["contact_traction", "contact_pressure", "normal_gap", "contact_active"]:
            values = written[key]
            assert np.array_equal(again.point_data[key][:, :dim] if values.ndim == 2
                                  else again.point_data[key], values), key


def test_a_result_s_arrays_are_read_only(half_disc):
    # An array edited in place would show in to_meshio but not in write(): they are read-only.
    body = half_disc.bodies["disc"]
    arrays = [body.coordinates, body.node_tags, body.displacement, body.cells, body.cell_tags,
              body.strain, body.stress, body.von_mises, half_disc.steps[0].force_primary]
    surface = body.surface
    arrays += [surface.nodes, surface.pressure, surface.mean_pressure, surface.traction,
               surface.gap, surface.active]
    for array in arrays:
        assert not array.flags.writeable
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 0


def conforms(value, kind, path="summary"):
    """Whether `value` has exactly the keys and value shapes `kind` (a TypedDict) declares."""
    origin = typing.get_origin(kind)
    if typing.is_typeddict(kind):
        assert isinstance(value, dict), path
        hints = typing.get_type_hints(kind)
        assert set(value) <= set(hints), f"{path}: undeclared keys {set(value) - set(hints)}"
        missing = kind.__required_keys__ - set(value)
        assert not missing, f"{path}: missing keys {missing}"
        for key, item in value.items():
            conforms(item, hints[key], f"{path}.{key}")
    elif origin is typing.Union:  # Optional[X]: None, or an X
        if value is not None:
            declared = next(o for o in typing.get_args(kind) if o is not type(None))
            conforms(value, declared, path)
    elif origin is list:
        assert isinstance(value, list), path
        for k, item in enumerate(value):
            conforms(item, typing.get_args(kind)[0], f"{path}[{k}]")
    elif origin is dict or kind is object:
        assert kind is object or isinstance(value, dict), path
    elif kind is float:
        assert isinstance(value, (int, float)), f"{path}: {value!r}"
    else:
        assert isinstance(value, kind), f"{path}: {value!r} is not {kind}"


def test_the_typed_summary_describes_contact_and_single_body_summaries(half_disc):
    # A contact run, one with load steps (the 3D demo), one with an agreement check (its note),
    # and a case without contact.
    two_bodies = {"body": [
        {"name": "disc", "youngs_modulus": 1e3, "poisson_ratio": 0.3,
         "dirichlet": [{"group": "disc_top", "ux": 0.0, "uy": -0.02}]},
        {"name": "block", "youngs_modulus": 1e3, "poisson_ratio": 0.3,
         "dirichlet": [{"group": "block_base", "ux": 0.0, "uy": 0.0}]}]}
    checked = internodes.Case.from_dict({**two_bodies, "contact": {
        "bodies": ["disc", "block"], "surfaces": ["disc_contact", "block_contact"],
        "check_other_primary": True}})
    single = internodes.Case.from_dict({"body": two_bodies["body"][:1]})
    stepped = internodes.Case.from_toml(REPO / "geo" / "hemisphere_on_block.toml")
    mesh = internodes.Mesh.from_msh(REPO / "tests" / "fixtures" / "half_disc_on_block.msh")
    results = [half_disc, internodes.solve(checked, mesh=mesh), internodes.solve(single, mesh=mesh),
               internodes.solve(stepped)]
    notes = [c for c in results[1].summary["contact"]["accuracy"]["indicators"] if "note" in c]
    assert notes, "the agreement check's note is exercised"
    assert "contact" not in results[2].summary
    for result in results:
        conforms(result.summary, typed.Summary)
