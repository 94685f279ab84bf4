"""The examples run headless, and their numbers are the command line's."""

import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import REPO, comparable, read_summary

EXAMPLES = REPO / "python" / "examples"


def run_example(name, output):
    environment = dict(os.environ, MPLBACKEND="Agg")
    done = subprocess.run([sys.executable, str(EXAMPLES / name), str(output)], capture_output=True,
                          text=True, timeout=900, env=environment)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_approach_sweep_plots_the_cli_forces(cli, tmp_path):
    run_example("approach_sweep.py", tmp_path / "sweep")
    assert (tmp_path / "sweep" / "approach_sweep.png").stat().st_size > 10_000
    rows = np.loadtxt(tmp_path / "sweep" / "approach_sweep.csv", delimiter=",", skiprows=1)
    assert rows.shape == (10, 3) and (np.diff(rows[:, 1]) > 0).all()
    # The CLI on the sweep's first and last approach, with the example's mesh parameters.
    for approach, force, radius in rows[[0, -1]]:
        text = (REPO / "geo" / "hemisphere_on_block.toml").read_text()
        case = "\n".join(line for line in text.splitlines()
                         if not line.startswith(("load_steps", "output")))
        case = case.replace('mesh = "hemisphere_on_block.geo"', f'mesh = "{REPO / "geo" / "hemisphere_on_block.geo"}"')
        case = case.replace("uz = -0.01", f"uz = {-approach!r}")
        assert f"uz = {-approach!r}" in case
        (tmp_path / "case.toml").write_text(case)
        code, stderr = cli(tmp_path / "case.toml", tmp_path / "cli")
        assert code == 0, stderr
        contact = read_summary(tmp_path / "cli")["contact"]
        assert np.linalg.norm(contact["force_primary"]) == force
        assert contact["hertz_fit"]["a"] == radius


def test_gmsh_in_memory_gives_the_cli_answer_on_the_model_written_out(cli, tmp_path):
    gmsh = pytest.importorskip("gmsh")
    stdout = run_example("gmsh_in_memory.py", tmp_path / "example")
    assert "status converged" in stdout
    ours = read_summary(tmp_path / "example")

    # The same model, written to a (binary, so exact) file, solved by the CLI.
    from test_gmsh_in_memory import example

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        example("gmsh_in_memory").build_half_disc_on_block()
        gmsh.option.setNumber("Mesh.Binary", 1)
        gmsh.write(str(tmp_path / "model.msh"))
    finally:
        gmsh.finalize()
    from conftest import hertz_2d_case

    code, stderr = cli(hertz_2d_case(tmp_path, tmp_path / "model.msh"), tmp_path / "cli")
    assert code == 0, stderr
    theirs = read_summary(tmp_path / "cli")
    assert comparable(ours["contact"]) == comparable(theirs["contact"])
    assert comparable(ours["bodies"][0]) == comparable(theirs["bodies"][0])
