"""internodes.study: the refinement study of `internodes study`, from Python."""

import json
import subprocess

import numpy as np
import pytest

import internodes
from conftest import CLI, REPO

# The summary's keys that differ between two runs of the same study: wall-clock seconds.
RUN_DEPENDENT = {"seconds"}


def coarse_half_disc(folder):
    """geo/half_disc_on_block.geo coarsened to h_c = R/20, the disc pressed by 0.02: its case
    file in `folder`."""
    path = folder / "case.toml"
    path.write_text(f"""mesh = "{REPO / 'geo' / 'half_disc_on_block.geo'}"
geo_parameters = {{ h_c = 0.05, r_c = 0.25 }}
output = "out"

[contact]
bodies = ["disc", "block"]
surfaces = ["disc_contact", "block_contact"]
primary = "disc"

[[body]]
name = "disc"
youngs_modulus = 1000.0
poisson_ratio = 0.3
dirichlet = [{{ group = "disc_top", ux = 0.0, uy = -0.02 }}]

[[body]]
name = "block"
youngs_modulus = 1000.0
poisson_ratio = 0.3
dirichlet = [{{ group = "block_base", ux = 0.0, uy = 0.0 }}]
""")
    return path


def without_seconds(value):
    if isinstance(value, dict):
        return {k: without_seconds(v) for k, v in value.items() if k not in RUN_DEPENDENT}
    if isinstance(value, list):
        return [without_seconds(v) for v in value]
    return value


def test_a_study_gives_the_cli_files_and_typed_columns(tmp_path):
    case_file = coarse_half_disc(tmp_path)
    case = internodes.Case.from_toml(case_file)
    study = internodes.study(case, parameter="level", values=[0, 1, 2], output=tmp_path / "py")

    assert study.exit_code == 0 and study.parameter == "level" and study.folder == tmp_path / "py"
    assert np.array_equal(study.values, [0.0, 1.0, 2.0])
    assert study.h.shape == (3,) and np.all(np.diff(study.h) < 0)
    assert set(study.quantities) == {"force", "a", "p0", "max_pressure"}
    assert all(column.shape == (3,) and np.all(np.isfinite(column)) for column in study.quantities.values())
    force = study.estimates["force"]["estimate"]
    assert force["order"] > 0 and force["gci_fine"] > 0
    assert "Study(" in repr(study) and "force: p=" in repr(study)
    # The object's summary is the file, and the command line writes the same study.
    written = json.loads((tmp_path / "py" / "study.json").read_text())
    assert without_seconds(study.summary) == without_seconds(written)
    for name in ["study.csv", "study.md", "study.png", "level_2/summary.json"]:
        assert (tmp_path / "py" / name).is_file(), name

    done = subprocess.run([str(CLI), "study", str(case_file), "--parameter", "level=0,1,2", "--output",
                           str(tmp_path / "cli"), "--quiet"], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    cli = json.loads((tmp_path / "cli" / "study.json").read_text())
    assert without_seconds(cli) == without_seconds(written)


def test_a_parameter_the_script_does_not_use_is_refused(tmp_path):
    case = internodes.Case.from_toml(coarse_half_disc(tmp_path))
    with pytest.raises(internodes.InputError, match="does not use a parameter 'levle'.*level, R, gap"):
        internodes.study(case, parameter="levle", values=[0, 1], output=tmp_path / "typo")
    with pytest.raises(internodes.InputError, match="at least two values"):
        internodes.study(case, parameter="level", values=[0], output=tmp_path / "one")
    assert not (tmp_path / "typo").exists()
