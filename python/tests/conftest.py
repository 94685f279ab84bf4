"""Shared helpers of the Python module's tests: the repository, the command-line binary, and
case files written for both."""

import json
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
CLI = REPO / "target" / "release" / "internodes"

# The summary's keys that differ between two runs of the same case, at any depth: wall-clock
# seconds and memory.
RUN_DEPENDENT = {"timings", "seconds", "peak_memory_mb"}


@pytest.fixture(scope="session")
def cli():
    """Runs `internodes solve CASE --output OUT` and returns (exit code, stderr)."""
    if not CLI.is_file():
        pytest.fail(f"{CLI} is missing: build it first (`make build`, which `make test` runs)")

    def run(case, output):
        done = subprocess.run([str(CLI), "solve", str(case), "--output", str(output), "--quiet"],
                              capture_output=True, text=True, timeout=600)
        return done.returncode, done.stderr

    return run


def comparable(summary, drop=()):
    """A summary without the figures that depend on the run (and without the top-level keys
    `drop`, such as the mesh's name where one run read a file the other meshed itself)."""

    def strip(value):
        if isinstance(value, dict):
            return {k: strip(v) for k, v in value.items() if k not in RUN_DEPENDENT}
        if isinstance(value, list):
            return [strip(v) for v in value]
        return value

    return strip({k: v for k, v in summary.items() if k not in set(drop)})


def read_summary(folder):
    return json.loads((Path(folder) / "summary.json").read_text())


def hertz_2d_case(folder, mesh, **contact):
    """The 2D half-disc on block case file, on `mesh`, with extra `[contact]` keys."""
    extra = "".join(f"{k} = {json.dumps(v)}\n" for k, v in contact.items())
    text = f"""mesh = "{mesh}"

[contact]
bodies = ["disc", "block"]
surfaces = ["disc_contact", "block_contact"]
{extra}
[[body]]
name = "disc"
youngs_modulus = 1000.0
poisson_ratio = 0.3

[[body.dirichlet]]
group = "disc_top"
ux = 0.0
uy = -0.02

[[body]]
name = "block"
youngs_modulus = 1000.0
poisson_ratio = 0.3

[[body.dirichlet]]
group = "block_base"
ux = 0.0
uy = 0.0
"""
    path = Path(folder) / "case.toml"
    path.write_text(text)
    return path
