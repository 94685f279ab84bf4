"""What a validation suite returns to ``run.py``, which writes them all into ``validation/report/``.

A suite is a module with ``run_suite(binary: Path, quick: bool, out_dir: Path) -> SuiteResult``:
``binary`` is the internodes executable, ``quick`` asks for the coarsest levels only (``make test``;
the pass/fail thresholds stay the same), ``out_dir`` is the suite's folder inside the report, where
its PNG figures go (scratch files go under ``validation/build/``).

Every pass/fail figure is a ``compare.Check``: it passes when ``figure <= tolerance``, so errors are
expressed as non-negative numbers (relative errors, or distances in units of the interface
spacing). Figures that are information only (fitted rates, Hertz's force-approach law beside the
reference) go in ``text`` and ``data``, never in ``checks``.
"""

from __future__ import annotations

import hashlib
import json
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

from compare import Check


@dataclass
class Figure:
    """A PNG written by the suite into its ``out_dir``, with the caption the report shows."""

    caption: str
    path: Path


@dataclass
class SuiteResult:
    """One section of the report."""

    title: str
    checks: list[Check] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    text: str = ""
    data: dict = field(default_factory=dict)


GEO = Path(__file__).resolve().parent.parent / "geo"


class MeshFailed(RuntimeError):
    """gmsh could not mesh a geo script (the message ends with gmsh's output)."""


def mesh_geo(script: str, dim: int, parameters: dict, path: Path) -> Path:
    """gmsh ``geo/<script>.geo`` with ``-setnumber`` parameters into ``path`` (MSH 4.1).

    Cached: a stamp next to the mesh records the parameters and a hash of the geo script, so an
    edited script or other parameters mesh again.
    """
    geo = GEO / f"{script}.geo"
    stamp = path.with_suffix(".json")
    key = {"parameters": parameters, "geo_sha256": hashlib.sha256(geo.read_bytes()).hexdigest()}
    if path.is_file() and stamp.is_file() and json.loads(stamp.read_text()) == key:
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    command = ["gmsh", f"-{dim}", str(geo), "-format", "msh41", "-v", "1", "-o", str(path)]
    for name, value in parameters.items():
        command += ["-setnumber", name, str(value)]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0 or not path.is_file():
        raise MeshFailed(f"gmsh {geo.name} {parameters} failed: {(result.stdout + result.stderr)[-400:]}")
    stamp.write_text(json.dumps(key))
    return path
