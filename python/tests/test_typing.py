"""The type stubs describe the module as built, and the examples type-check against them."""

import subprocess
import sys

import pytest

from conftest import REPO

pytest.importorskip("mypy")


CONFIG = str(REPO / "python" / "mypy.ini")


def run(folder, *arguments):
    done = subprocess.run([sys.executable, "-m", *arguments], capture_output=True, text=True,
                          timeout=600, cwd=folder)
    return done.returncode, done.stdout + done.stderr


def test_the_stubs_match_the_native_module(tmp_path):
    # From a folder without the package's source, so that the installed module is checked.
    code, output = run(tmp_path, "mypy.stubtest", "internodes", "--mypy-config-file", CONFIG)
    assert code == 0, output


def test_the_examples_type_check():
    code, output = run(REPO / "python", "mypy", "--config-file", CONFIG, "examples")
    assert code == 0, output
