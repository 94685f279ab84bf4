"""The solve releases the GIL, so that threads run cases side by side; progress goes to
Python's logging, which is silent unless configured."""

import logging
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import internodes
from conftest import REPO

CASE = REPO / "geo" / "hemisphere_on_block.toml"


def test_python_threads_run_during_a_solve():
    mesh = internodes.Mesh.from_geo(REPO / "geo" / "hemisphere_on_block.geo",
                                    {"h_c": 0.015, "r_c": 0.16, "h_far": 0.5, "d_far": 1.0})
    case = internodes.Case.from_toml(CASE)
    ticks, done = [], threading.Event()

    def count():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    counter = threading.Thread(target=count)
    counter.start()
    start = time.perf_counter()
    try:
        internodes.solve(case, mesh=mesh)
    finally:
        done.set()
        counter.join()
    seconds = time.perf_counter() - start
    during = [t for t in ticks if start < t < start + seconds]
    # A solve holding the GIL would stop the counter for its whole length (seconds).
    assert seconds > 0.5 and len(during) > 100 * seconds, (seconds, len(during))
    assert max(np.diff(during)) < 0.25 * seconds


def test_cases_side_by_side_give_the_answers_of_cases_in_turn():
    mesh = internodes.Mesh.from_msh(REPO / "tests" / "fixtures" / "half_disc_on_block.msh")

    def case(approach):
        return internodes.Case.from_dict({
            "contact": {"bodies": ["disc", "block"], "surfaces": ["disc_contact", "block_contact"]},
            "body": [{"name": "disc", "youngs_modulus": 1e3, "poisson_ratio": 0.3,
                      "dirichlet": [{"group": "disc_top", "ux": 0.0, "uy": -approach}]},
                     {"name": "block", "youngs_modulus": 1e3, "poisson_ratio": 0.3,
                      "dirichlet": [{"group": "block_base", "ux": 0.0, "uy": 0.0}]}]})

    approaches = [0.005, 0.01, 0.015, 0.02]
    in_turn = [internodes.solve(case(d), mesh=mesh) for d in approaches]
    with ThreadPoolExecutor(max_workers=2) as pool:
        side_by_side = list(pool.map(lambda d: internodes.solve(case(d), mesh=mesh), approaches))
    for a, b in zip(in_turn, side_by_side):
        assert a.summary["contact"]["force_primary"] == b.summary["contact"]["force_primary"]
        assert np.array_equal(a.bodies["disc"].displacement, b.bodies["disc"].displacement)


def test_progress_goes_to_logging(caplog):
    with caplog.at_level(logging.INFO, logger="internodes"):
        internodes.solve(internodes.Case.from_toml(REPO / "geo" / "half_disc_on_block.toml"))
    messages = [r.getMessage() for r in caplog.records if r.name.startswith("internodes.")]
    assert any("contact: 'disc'" in m or "contact: 'block'" in m for m in messages), messages
    assert any(m.startswith("contact status: converged") for m in messages), messages


def test_the_levels_are_the_command_line_s(caplog):
    # INFO is the command line's default log, DEBUG its -v, internodes.TRACE its -vv.
    with caplog.at_level(internodes.TRACE, logger="internodes"):
        internodes.solve(internodes.Case.from_toml(REPO / "geo" / "half_disc_on_block.toml"))

    def at(level):
        return [r.getMessage() for r in caplog.records
                if r.name.startswith("internodes.") and r.levelno == level]

    info, debug, trace = at(logging.INFO), at(logging.DEBUG), at(internodes.TRACE)
    assert any(m.startswith("contact status: converged") for m in info), info
    assert not any("iteration " in m or "GMRES" in m for m in info), info
    assert any(m.startswith("  iteration ") for m in debug), debug
    assert any("\n  checks:\n" in m for m in debug), debug
    assert any("coupled GMRES: " in m for m in trace), trace


def test_the_module_is_silent_by_default():
    script = ("import internodes; r = internodes.solve(internodes.Case.from_toml(%r)); "
              "assert r.status == 'converged'" % str(REPO / "geo" / "half_disc_on_block.toml"))
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert (done.stdout, done.stderr) == ("", "")


def test_each_solve_has_its_own_threads_and_the_answer_does_not_depend_on_them():
    mesh = internodes.Mesh.from_msh(REPO / "tests" / "fixtures" / "half_disc_on_block.msh")
    case = internodes.Case.from_toml(REPO / "geo" / "half_disc_on_block.toml")
    one, two = (internodes.solve(case, mesh=mesh, threads=n) for n in (1, 2))
    assert one.summary["contact"]["force_primary"] == two.summary["contact"]["force_primary"]
    assert np.array_equal(one.bodies["disc"].displacement, two.bodies["disc"].displacement)
    with pytest.raises(ValueError, match="threads must be at least 1"):
        internodes.solve(case, mesh=mesh, threads=0)
