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


# ---------------------------------------------------------------------------
# The [contact] table of a case file
# ---------------------------------------------------------------------------

# Keys of the [contact] table before the solver rewrite (issue 11), replaced by bodies / surfaces / primary.
OLD_CONTACT_KEYS = ("primary_surface", "secondary", "secondary_surface")


def contact_table(bodies: tuple[str, str], surfaces: tuple[str, str], primary: str = "auto",
                  formulation: str = "frictionless", **extra) -> str:
    """The ``[contact]`` table of a case file, in the form of the rewritten solver (issue 11).

    ``bodies`` are the two bodies in contact, ``surfaces`` their candidate surfaces in the same
    order, ``primary`` "auto" or one of the two body names (an explicit choice). ``extra`` are
    further keys written verbatim as TOML values (``load_steps = [...]``, ``max_iterations``...).
    """
    if primary != "auto" and primary not in bodies:
        raise ValueError(f"primary '{primary}' is neither 'auto' nor one of the bodies {bodies}")
    lines = ["[contact]", f"bodies = {json.dumps(list(bodies))}", f"surfaces = {json.dumps(list(surfaces))}",
             f'primary = "{primary}"', f'formulation = "{formulation}"']
    lines += [f"{key} = {json.dumps(value)}" for key, value in extra.items()]
    return "\n".join(lines) + "\n"


def modern_contact(table: dict) -> dict:
    """A ``[contact]`` table (parsed TOML) in the rewritten form: the old ``primary`` /
    ``primary_surface`` / ``secondary`` / ``secondary_surface`` keys become ``bodies``, ``surfaces``
    and an explicit ``primary``; a table already in the new form is returned unchanged.

    Lets the suites that take their case from ``geo/*.toml`` write the new form whichever form
    those templates are in."""
    if not any(key in table for key in OLD_CONTACT_KEYS):
        return dict(table)
    new = {k: v for k, v in table.items() if k not in OLD_CONTACT_KEYS + ("primary",)}
    return {"bodies": [table["primary"], table["secondary"]],
            "surfaces": [table["primary_surface"], table["secondary_surface"]],
            "primary": table["primary"], **new}


def contact_sides(table: dict) -> dict[str, str]:
    """Body name -> candidate surface of a ``[contact]`` table (either form)."""
    table = modern_contact(table)
    return dict(zip(table["bodies"], table["surfaces"]))


def surface_spacing(msh: Path, group: str, dim: int, radius: float) -> float:
    """Mean length of the edges of a surface group with both ends within ``radius`` of the contact axis."""
    import gmsh
    import numpy as np

    gmsh.initialize(["gmsh", "-v", "0"])
    try:
        gmsh.open(str(msh))
        tags, coords, _ = gmsh.model.mesh.getNodes()
        x = np.zeros((int(tags.max()) + 1, 3))
        x[tags.astype(int)] = coords.reshape(-1, 3)
        groups = {gmsh.model.getPhysicalName(d, t): (d, t) for d, t in gmsh.model.getPhysicalGroups(dim - 1)}
        if group not in groups:
            raise ValueError(f"{msh}: no physical group '{group}'")
        facets = []
        for entity in gmsh.model.getEntitiesForPhysicalGroup(*groups[group]):
            _, _, nodes = gmsh.model.mesh.getElements(dim - 1, entity)
            facets += [n.astype(int).reshape(-1, dim) for n in nodes]
    finally:
        gmsh.finalize()
    facets = np.concatenate(facets)
    edges = np.concatenate([facets[:, [i, (i + 1) % dim]] for i in range(dim if dim == 3 else 1)])
    edges = np.unique(np.sort(edges, axis=1), axis=0)
    r = np.linalg.norm(x[:, : dim - 1], axis=1)
    near = edges[(r[edges] <= radius).all(axis=1)]
    if len(near) == 0:
        return float("nan")
    return float(np.linalg.norm(x[near[:, 0]] - x[near[:, 1]], axis=1).mean())


def json_safe(value):
    """Replace NaN / inf by None, keys by strings and numpy scalars by Python ones, recursively."""
    import math

    import numpy as np

    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, np.generic):
        return json_safe(value.item())
    return value
