"""The module runs the library's solve: its results equal the command line's, bit for bit."""

import re

import h5py
import numpy as np
import pytest

import internodes
from conftest import REPO, comparable, hertz_2d_case, read_summary


def datasets(path):
    """Every dataset of an HDF5 file, by name."""
    found = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, item: found.__setitem__(name, item[()])
                     if isinstance(item, h5py.Dataset) else None)
    return found


def csv_without_seconds(folder):
    """force_displacement.csv without its wall-clock column."""
    rows = [line.split(",") for line in (folder / "force_displacement.csv").read_text().splitlines()]
    keep = [k for k, name in enumerate(rows[0]) if name != "seconds"]
    assert len(keep) == len(rows[0]) - 1 and len(rows) > 1
    return [[row[k] for k in keep] for row in rows]


@pytest.mark.parametrize("toml", ["hemisphere_on_block.toml", "half_disc_on_block.toml"])
def test_a_geo_case_gives_the_cli_answer_and_files(cli, tmp_path, toml):
    case_file = REPO / "geo" / toml
    code, stderr = cli(case_file, tmp_path / "cli")
    assert code == 0, stderr

    result = internodes.solve(internodes.Case.from_toml(case_file))
    assert (result.exit_code, result.status, result.solved, result.accurate) == (0, "converged", True, True)
    # The CLI names the mesh it wrote (out/mesh.msh), the module the .geo it meshed.
    assert comparable(result.summary, ["mesh"]) == comparable(read_summary(tmp_path / "cli"), ["mesh"])

    result.write(tmp_path / "py")
    assert comparable(read_summary(tmp_path / "py"), ["mesh"]) == comparable(read_summary(tmp_path / "cli"), ["mesh"])
    ours, theirs = datasets(tmp_path / "py" / "solution.h5"), datasets(tmp_path / "cli" / "solution.h5")
    assert ours.keys() == theirs.keys() and len(ours) > 10
    for name in theirs:
        assert np.array_equal(ours[name], theirs[name]), name
    for name in ["mesh.msh", "solution.xdmf"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    assert csv_without_seconds(tmp_path / "py") == csv_without_seconds(tmp_path / "cli")


def test_the_arrays_are_the_files_fields(tmp_path):
    case = internodes.Case.from_toml(REPO / "geo" / "half_disc_on_block.toml")
    result = internodes.solve(case)
    result.write(tmp_path)
    # Earlier results are replaced only on request, the folder named; other files stay.
    (tmp_path / "notes.txt").write_text("mine")
    written = (tmp_path / "summary.json").stat().st_mtime_ns
    with pytest.raises(FileExistsError,
                       match=rf"^{re.escape(str(tmp_path))} holds results already \(solution.xdmf, solution.h5, "
                             r"summary.json, force_displacement.csv, force_displacement.png, "
                             r"mesh.msh\): pass overwrite=True to replace them$"):
        result.write(tmp_path)
    assert (tmp_path / "summary.json").stat().st_mtime_ns == written
    assert result.write(tmp_path, overwrite=True) == tmp_path
    assert (tmp_path / "notes.txt").read_text() == "mine"
    # A folder of other files only is written into.
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    result.write(other)
    assert (other / "summary.json").is_file() and (other / "notes.txt").read_text() == "mine"
    files = datasets(tmp_path / "solution.h5")
    disc, block = result.bodies["disc"], result.bodies["block"]
    n = disc.displacement.shape[0]
    assert disc.displacement.shape == (n, 2) and disc.coordinates.shape == (n, 2)
    displacement = files["fields/displacement"]
    assert np.array_equal(displacement[:n, :2], disc.displacement)
    assert np.array_equal(displacement[n:n + block.displacement.shape[0], :2], block.displacement)
    assert disc.stress.shape == (disc.cells.shape[0], 3, 3)
    assert np.array_equal(disc.von_mises, files["fields/von_mises"][:disc.cells.shape[0]].ravel())
    # The contact surfaces: pressure where active, and the force balance of the summary.
    surface = disc.surface
    assert surface.active.dtype == bool and surface.active.any()
    assert (surface.pressure[~surface.active] == 0).all()
    assert result.summary["contact"]["active_primary"] + result.summary["contact"]["active_secondary"] == \
        disc.surface.active.sum() + block.surface.active.sum()


def test_a_case_built_in_code_equals_its_file(cli, tmp_path):
    mesh = REPO / "tests" / "fixtures" / "half_disc_on_block.msh"
    case_file = hertz_2d_case(tmp_path, mesh)
    from_file = internodes.solve(internodes.Case.from_toml(case_file))
    table = {
        "mesh": str(mesh),
        "contact": {"bodies": ["disc", "block"], "surfaces": ["disc_contact", "block_contact"]},
        "body": [
            {"name": "disc", "youngs_modulus": 1000.0, "poisson_ratio": 0.3,
             "dirichlet": [{"group": "disc_top", "ux": 0.0, "uy": -0.02}]},
            {"name": "block", "youngs_modulus": 1000, "poisson_ratio": 0.3,
             "dirichlet": [{"group": "block_base", "ux": 0, "uy": 0}]},
        ],
    }
    in_code = internodes.solve(internodes.Case.from_dict(table, name=str(case_file)))
    assert comparable(in_code.summary) == comparable(from_file.summary)
    # And a Mesh object passed to solve() stands for the case's mesh.
    given = internodes.solve(internodes.Case.from_dict({k: v for k, v in table.items() if k != "mesh"}),
                             mesh=internodes.Mesh.from_msh(mesh))
    assert np.array_equal(given.bodies["disc"].displacement, from_file.bodies["disc"].displacement)
