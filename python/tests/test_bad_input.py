"""Bad input raises an exception with the command line's message; nothing crashes the
interpreter."""

import math
from decimal import Decimal
from fractions import Fraction

import pytest

import internodes
from conftest import REPO, hertz_2d_case

MESH = REPO / "tests" / "fixtures" / "half_disc_on_block.msh"


def cli_error(cli, case_file, tmp_path):
    """The message the command line prints after `error: ` (with its `caused by` lines)."""
    code, stderr = cli(case_file, tmp_path / "cli-out")
    assert code == 1, stderr
    assert stderr.startswith("error: "), stderr
    return stderr[len("error: "):].rstrip("\n")


@pytest.mark.parametrize("fault", [
    ("mesh = \"{mesh}\"\n[contact\n", "a syntax error"),
    ("mesh = \"{mesh}\"\ncolour = 1\n[[body]]\nname = \"disc\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n", "an unknown key"),
    ("mesh = \"{mesh}\"\n[[body]]\nname = \"disc\"\nyoungs_modulus = \"stiff\"\npoisson_ratio = 0.3\n", "a string for a number"),
    ("mesh = \"{mesh}\"\n[[body]]\nname = \"disc\"\nyoungs_modulus = -1.0\npoisson_ratio = 0.3\n", "a negative modulus"),
    ("mesh = \"{mesh}\"\n[[body]]\nname = \"ball\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n", "a body the mesh lacks"),
    ("mesh = \"missing.msh\"\n[[body]]\nname = \"disc\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n", "a missing mesh"),
], ids=lambda fault: fault[1])
def test_a_bad_case_file_raises_the_cli_message(cli, tmp_path, fault):
    case_file = tmp_path / "bad.toml"
    case_file.write_text(fault[0].format(mesh=MESH))
    expected = cli_error(cli, case_file, tmp_path)
    with pytest.raises(internodes.InputError) as raised:
        internodes.solve(internodes.Case.from_toml(case_file))
    assert str(raised.value) == expected
    assert isinstance(raised.value, ValueError)


def test_a_missing_case_file_names_it():
    with pytest.raises(internodes.InputError, match="cannot read case file .*nowhere.toml"):
        internodes.Case.from_toml("nowhere.toml")


@pytest.mark.parametrize("table, match", [
    ({"body": []}, "the case names no body"),
    ({"body": [{"name": "disc", "youngs_modulus": None, "poisson_ratio": 0.3}]},
     r"body\[0\].youngs_modulus is None"),
    ({"body": [{"name": "disc", "youngs_modulus": 1.0, "poisson_ratio": 0.3}], "solver": {"rtol": 2.0}},
     r"rtol must be in \(0, 1\)"),
    # Both bodies named: a pair's body without a [[body]] table is refused first.
    ({"body": [{"name": "disc", "youngs_modulus": 1.0, "poisson_ratio": 0.3},
               {"name": "block", "youngs_modulus": 1.0, "poisson_ratio": 0.3}],
      "contact": {"bodies": ["disc", "block"], "surfaces": ["a", "b"], "load_steps": []}},
     "load_steps"),
    ({"body": [{"name": "disc", "youngs_modulus": 1.0, "poisson_ratio": 0.3}], "mesh": object()},
     r"case 'study' \(from a dict\): mesh: a value of type object \(<object object at .*>\) is "
     "not a case value"),
], ids=["no body", "null modulus", "rtol", "empty load steps", "an object for a path"])
def test_a_bad_dict_raises_input_error(table, match):
    with pytest.raises(internodes.InputError, match=match):
        internodes.Case.from_dict(table, name="study")


def test_a_case_without_mesh_needs_one_at_solve():
    case = internodes.Case.from_dict({"body": [{"name": "disc", "youngs_modulus": 1.0, "poisson_ratio": 0.3}]})
    assert case.mesh is None
    with pytest.raises(internodes.InputError, match="names no mesh: .* pass mesh= to solve"):
        internodes.solve(case)


@pytest.mark.parametrize("content, match", [
    (b"", "the file is empty"),
    (b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n", "MSH format version 2.2 is not supported"),
    (b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\n", r"bad.msh:\d+"),
])
def test_a_bad_mesh_file_raises_input_error(tmp_path, content, match):
    (tmp_path / "bad.msh").write_bytes(content)
    with pytest.raises(internodes.InputError, match=match):
        internodes.Mesh.from_msh(tmp_path / "bad.msh")


def test_an_empty_gmsh_model_raises_input_error():
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize()
    try:
        with pytest.raises(internodes.InputError, match="^gmsh model.*: no body found"):
            internodes.Mesh.from_gmsh()
    finally:
        gmsh.finalize()


def test_gmsh_after_finalize_raises_input_error():
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize()
    gmsh.finalize()
    with pytest.raises(internodes.InputError,
                       match=r"gmsh is not initialized: call gmsh.initialize\(\)"):
        internodes.Mesh.from_gmsh()


def test_a_gmsh_model_without_bodies_raises_input_error():
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.occ.addRectangle(0, 0, 0, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.model.mesh.generate(2)
        with pytest.raises(internodes.InputError, match="gmsh model.*no .*surface"):
            internodes.Mesh.from_gmsh()
    finally:
        gmsh.finalize()


def test_a_contact_problem_not_solved_is_a_status_as_in_the_cli(cli, tmp_path):
    # One iteration cannot settle the active set: the CLI writes the last iterate and exits 2.
    case_file = hertz_2d_case(tmp_path, MESH, max_iterations=1)
    code, stderr = cli(case_file, tmp_path / "cli")
    result = internodes.solve(internodes.Case.from_toml(case_file))
    assert (result.exit_code, code) == (2, 2)
    assert (result.status, result.solved, result.accurate) == ("iteration-limit", False, False)
    with pytest.raises(internodes.NotSolvedError) as raised:
        result.raise_for_status()
    assert stderr.startswith(f"error: {raised.value} (see ")


def test_an_unknown_mesh_parameter_is_refused_as_in_a_case_file(cli, tmp_path):
    # `Level` for the script's `level`: gmsh would ignore it and mesh the default level.
    geo = REPO / "geo" / "half_disc_on_block.geo"
    case_file = tmp_path / "case.toml"
    case_file.write_text(f'mesh = "{geo}"\ngeo_parameters = {{ Level = 2 }}\n'
                         '[[body]]\nname = "disc"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n')
    expected = cli_error(cli, case_file, tmp_path)
    prefix = f"case file {case_file}: "
    assert expected.startswith(prefix) and "does not use a parameter 'Level'" in expected
    with pytest.raises(internodes.InputError) as raised:
        internodes.Mesh.from_geo(geo, {"Level": 2})
    assert str(raised.value) == expected[len(prefix):]
    with pytest.raises(internodes.InputError, match="expected a finite number"):
        internodes.Mesh.from_geo(geo, {"level": float("nan")})


def disc_dict(youngs_modulus=1e3, poisson_ratio=0.3, uy=-0.02, load_steps=(0.5, 1.0)):
    return {
        "contact": {"bodies": ["disc", "block"], "surfaces": ["disc_contact", "block_contact"],
                    "load_steps": load_steps},
        "body": [{"name": "disc", "youngs_modulus": youngs_modulus, "poisson_ratio": poisson_ratio,
                  "dirichlet": [{"group": "disc_top", "ux": 0.0, "uy": uy}]},
                 {"name": "block", "youngs_modulus": 1e3, "poisson_ratio": 0.3,
                  "dirichlet": [{"group": "block_base", "ux": 0, "uy": 0}]}]}


def test_numpy_scalars_and_arrays_are_numbers():
    np = pytest.importorskip("numpy")
    mesh = internodes.Mesh.from_msh(MESH)
    plain = internodes.solve(internodes.Case.from_dict(disc_dict()), mesh=mesh)
    numpy = internodes.solve(internodes.Case.from_dict(disc_dict(
        youngs_modulus=np.int64(1000), poisson_ratio=np.array(0.3), uy=np.float64(-0.02),
        load_steps=np.array([0.5, 1.0]))), mesh=mesh)
    assert plain.summary["contact"]["force_primary"] == numpy.summary["contact"]["force_primary"]
    # float32 holds 0.3 as 0.30000001192...: accepted, as that number.
    case = internodes.Case.from_dict(disc_dict(poisson_ratio=np.float32(0.3), uy=np.float32(-0.02)))
    assert internodes.solve(case, mesh=mesh).status == "converged"
    geo = REPO / "geo" / "half_disc_on_block.geo"
    assert internodes.Mesh.from_geo(geo, {"level": np.int64(0)}).dim == 2
    assert internodes.Mesh.from_geo(geo, {"level": np.array(0.0)}).dim == 2


@pytest.mark.parametrize("material, match", [
    ({"youngs_modulus": 0.0}, "Young's modulus must be positive and finite, got 0"),
    ({"youngs_modulus": -1e3}, "Young's modulus must be positive and finite, got -1000"),
    ({"poisson_ratio": 0.5}, r"Poisson's ratio must lie in \(-1, 0.5\)"),
    ({"poisson_ratio": -1.0}, r"Poisson's ratio must lie in \(-1, 0.5\)"),
], ids=["E = 0", "E < 0", "nu = 0.5", "nu = -1"])
def test_a_bad_material_is_refused_by_from_dict(material, match):
    np = pytest.importorskip("numpy")
    with pytest.raises(internodes.InputError,
                       match=f"case 'study' \\(from a dict\\): body 'disc': {match}"):
        internodes.Case.from_dict(disc_dict(**material), name="study")
    # NumPy values are checked alike.
    with pytest.raises(internodes.InputError, match=match):
        internodes.Case.from_dict(disc_dict(**{k: np.float64(v) for k, v in material.items()}))


@pytest.mark.parametrize("value, says", [
    (math.nan, "NaN"), (math.inf, "inf"), (-math.inf, "-inf"), (Decimal("NaN"), "NaN"),
    (Decimal("Infinity"), "Decimal\\('Infinity'\\)"), (Fraction(10**400), "Fraction"),
], ids=["nan", "inf", "-inf", "Decimal nan", "Decimal inf", "a Fraction beyond floats"])
def test_nan_and_inf_in_a_dict_name_the_key(value, says):
    table = disc_dict(uy=value)
    with pytest.raises(internodes.InputError,
                       match=rf"^case 'study' \(from a dict\): body\[0\]\.dirichlet\[0\]\.uy: "
                             rf"{says}.* is not a number a case can hold"):
        internodes.Case.from_dict(table, name="study")
    table = disc_dict()
    table["contact"]["friction_coefficient"] = value
    with pytest.raises(internodes.InputError, match=r"contact\.friction_coefficient: "):
        internodes.Case.from_dict(table)
    np = pytest.importorskip("numpy")
    with pytest.raises(internodes.InputError, match=r"contact\.load_steps\[1\]: NaN"):
        internodes.Case.from_dict(disc_dict(load_steps=np.array([0.5, np.nan])))


@pytest.mark.parametrize("fault, match", [
    ("friction_coefficient = nan", r"\[contact\]: friction_coefficient must be a finite number > 0, got NaN"),
    ("load_steps = [0.5, inf]", "load_steps"),
], ids=["nan", "inf"])
def test_nan_and_inf_in_a_case_file_name_the_key(tmp_path, fault, match):
    case_file = hertz_2d_case(tmp_path, MESH, formulation="coulomb")
    text = case_file.read_text().replace("[contact]\n", f"[contact]\n{fault}\n")
    if "friction" not in fault:
        text = text.replace('formulation = "coulomb"\n', "")
    case_file.write_text(text)
    # Refused when the case is read or, for the pair's keys, when its contact is set up.
    with pytest.raises(internodes.InputError, match=f"case file {case_file}: .*{match}"):
        internodes.solve(internodes.Case.from_toml(case_file))


def test_fractions_and_decimals_are_the_nearest_floats():
    mesh = internodes.Mesh.from_msh(MESH)
    floats = internodes.solve(internodes.Case.from_dict(disc_dict(load_steps=[0.5, 1.0])), mesh=mesh)
    exact = internodes.Case.from_dict(disc_dict(youngs_modulus=Decimal("1000"),
                                                poisson_ratio=Fraction(3, 10),
                                                uy=Decimal("-0.02"),
                                                load_steps=[Fraction(1, 2), Decimal(1)]))
    assert exact.load_steps == [0.5, 1.0]
    assert (internodes.solve(exact, mesh=mesh).summary["contact"]["force_primary"]
            == floats.summary["contact"]["force_primary"])


def test_a_case_from_a_dict_is_not_called_a_case_file():
    pickle = pytest.importorskip("pickle")
    bad = {"body": [{"name": "ball", "youngs_modulus": 1.0, "poisson_ratio": 0.3}]}
    with pytest.raises(internodes.InputError) as raised:
        internodes.solve(internodes.Case.from_dict(bad, name="sweep"),
                         mesh=internodes.Mesh.from_msh(MESH))
    message = str(raised.value)
    assert message.startswith("case 'sweep' (from a dict): ") and "case file" not in message
    # A pickled case is still a dict's.
    case = pickle.loads(pickle.dumps(internodes.Case.from_dict(bad, name="sweep")))
    with pytest.raises(internodes.InputError, match=r"^case 'sweep' \(from a dict\): body 'ball'"):
        internodes.solve(case, mesh=internodes.Mesh.from_msh(MESH))
    with pytest.raises(internodes.InputError, match=r"^case 'case' \(from a dict\): body 'disc': Young's modulus"):
        internodes.Case.from_dict(disc_dict(youngs_modulus=-1.0))
    # A case file keeps its name.
    with pytest.raises(internodes.InputError, match="^cannot read case file"):
        internodes.Case.from_toml("nowhere.toml")
