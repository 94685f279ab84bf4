"""Compare the output of ``internodes solve --export-matrices`` with the
dolfinx reference of ``dolfinx_reference.py``.

Every figure is a relative error, compared with a tolerance (``TOLERANCES``):

* matrices (stiffness K of each body, surface mass M of each boundary group
  named in the case): max_ij |A_ours - A_ref| / max_ij |A_ref| over the union
  of both sparsity patterns, in the internodes numbering;
* mass sum: |sum_ij M_ours - |G|| / |G|, with |G| the length / area of the
  group computed from gmsh's elements (sum_ij M_ij = int_G 1 ds);
* displacement: ||u - u_ref||_2 / ||u_ref||_2 and max |u - u_ref| / max |u_ref|
  over all nodes and the 3 stored components (z must be 0 in 2D);
* reactions: max over groups and components |R - R_ref| / max |R_ref|;
* strain, stress, von Mises: max over cells and components of
  |T - T_ref| / max |T_ref| (cells matched by their sorted node numbers);
* mesh tags (a count, must be 0): rows of /mesh/node_tag, node_body,
  cell_tag, cell_body inconsistent with the gmsh file.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np
import scipy.io
import scipy.sparse as sp

from dolfinx_reference import Body, Case, ReferenceFailure, ReferenceModel

# Assembly differs only by the summation order: round-off level.
MATRIX_TOLERANCE = 1e-12
# Solutions go through a linear solve: round-off times the condition number.
SOLUTION_TOLERANCE = 1e-8
TOLERANCES = {
    "stiffness": MATRIX_TOLERANCE,
    "surface mass": MATRIX_TOLERANCE,
    "mass sum": MATRIX_TOLERANCE,
    "displacement L2": SOLUTION_TOLERANCE,
    "displacement max": SOLUTION_TOLERANCE,
    "reactions": SOLUTION_TOLERANCE,
    "strain": SOLUTION_TOLERANCE,
    "stress": SOLUTION_TOLERANCE,
    "von Mises": SOLUTION_TOLERANCE,
    "mesh tags": 0,  # a count of wrong rows
}


@dataclass
class Check:
    """One line of the result table."""

    check: str
    case: str
    figure: float
    tolerance: float
    note: str = ""

    def __post_init__(self):
        self.figure = float(self.figure)

    @property
    def passed(self) -> bool:
        """figure <= tolerance (a NaN figure fails)."""
        return bool(self.figure <= self.tolerance)


def failure(check: str, case: str, note: str) -> Check:
    """A check that could not be evaluated (missing output, error): it fails."""
    return Check(check, case, math.nan, TOLERANCES.get(check, 0.0), note)


# ---------------------------------------------------------------------------
# Reading the internodes output
# ---------------------------------------------------------------------------


class MissingOutput(RuntimeError):
    """An expected internodes output file / entry is absent or malformed."""


@dataclass
class BodyOutput:
    """The rows of one body in the internodes output (local node numbering)."""

    summary: dict  # the body's entry of summary.json
    cells: np.ndarray  # (c, dim + 1) local node indices
    geometry: np.ndarray  # (n, 3) node coordinates
    displacement: np.ndarray  # (n, 3)
    node_tag: np.ndarray  # (n,) gmsh node tags
    node_body: np.ndarray  # (n,)
    strain: np.ndarray  # (c, 9) 3x3 row-major
    stress: np.ndarray  # (c, 9)
    von_mises: np.ndarray  # (c,)
    cell_tag: np.ndarray  # (c,) gmsh element tags
    cell_body: np.ndarray  # (c,)


class InternodesOutput:
    """An output folder of ``internodes solve``: summary.json, solution.h5, matrices/."""

    NODE_DATASETS = ("mesh/geometry", "fields/displacement", "mesh/node_tag", "mesh/node_body")
    CELL_DATASETS = ("fields/strain", "fields/stress", "fields/von_mises", "mesh/cell_tag", "mesh/cell_body")
    DATASETS = ("mesh/topology",) + NODE_DATASETS + CELL_DATASETS

    def __init__(self, folder: Path):
        self.folder = Path(folder)
        summary = json.loads(self._file("summary.json").read_text())
        self.dim = summary["dimension"]
        with h5py.File(self._file("solution.h5"), "r") as h5:
            missing = [d for d in self.DATASETS if d not in h5]
            if missing:
                raise MissingOutput(f"{self.folder / 'solution.h5'}: missing datasets {missing}")
            data = {d: h5[d][()] for d in self.DATASETS}
        self.bodies = {b["name"]: self._body(b, data) for b in summary["bodies"]}

    def _file(self, name: str) -> Path:
        """Path of an output file, which must exist."""
        path = self.folder / name
        if not path.is_file():
            raise MissingOutput(f"missing internodes output {path}")
        return path

    def _body(self, b: dict, data: dict) -> BodyOutput:
        """Slice the rows of body b out of the global arrays."""
        nodes = slice(b["node_offset"], b["node_offset"] + b["num_nodes"])
        cells = slice(b["cell_offset"], b["cell_offset"] + b["num_cells"])
        local = data["mesh/topology"][cells] - b["node_offset"]
        if local.size and (local.min() < 0 or local.max() >= b["num_nodes"]):
            raise MissingOutput(f"{self.folder}: cells of body '{b['name']}' use nodes of another body")
        fields = {d.split("/")[1]: data[d][nodes] for d in self.NODE_DATASETS}
        fields |= {d.split("/")[1]: data[d][cells] for d in self.CELL_DATASETS}
        return BodyOutput(b, local, **fields)

    def body(self, name: str) -> BodyOutput:
        """The output of body ``name`` (clear error if absent)."""
        if name not in self.bodies:
            raise MissingOutput(f"{self.folder}/summary.json: no body '{name}' (bodies: {sorted(self.bodies)})")
        return self.bodies[name]

    def matrix(self, name: str, shape: tuple[int, int]) -> sp.csr_matrix:
        """matrices/<name>.mtx as a CSR matrix of the given shape."""
        path = self._file(f"matrices/{name}.mtx")
        matrix = sp.csr_matrix(scipy.io.mmread(path))
        if matrix.shape != shape:
            raise MissingOutput(f"{path}: shape {matrix.shape}, expected {shape}")
        return matrix


# ---------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------


def relative_max(ours, reference) -> float:
    """max |ours - reference| / max |reference| (works for arrays and sparse matrices)."""
    difference = abs(ours - reference).max()
    return float(difference / abs(reference).max())


def relative_l2(ours: np.ndarray, reference: np.ndarray) -> float:
    """||ours - reference||_2 / ||reference||_2 over all entries."""
    return float(np.linalg.norm(ours - reference) / np.linalg.norm(reference))


def von_mises(stress: np.ndarray) -> np.ndarray:
    """sqrt(3/2 s:s), s the deviator of the 3x3 stresses (rows of 9)."""
    s = stress.reshape(-1, 3, 3)
    deviator = s - np.trace(s, axis1=1, axis2=2)[:, None, None] * np.eye(3) / 3
    return np.sqrt(1.5 * (deviator**2).sum(axis=(1, 2)))


def pad3(u: np.ndarray) -> np.ndarray:
    """Displacements (n, dim) as (n, 3) with zero z in 2D."""
    return np.pad(u, ((0, 0), (0, 3 - u.shape[1])))


def cell_order(ours: np.ndarray, reference: np.ndarray, where: str) -> np.ndarray:
    """Permutation p with sorted(reference[p[k]]) == sorted(ours[k]) for every cell k."""
    index = {tuple(c): k for k, c in enumerate(np.sort(reference, axis=1))}
    keys = [tuple(c) for c in np.sort(ours, axis=1)]
    missing = [k for k in keys if k not in index]
    if missing or len(ours) != len(reference):
        raise MissingOutput(f"{where}: {len(ours)} internodes cells, {len(reference)} dolfinx cells, "
                            f"{len(missing)} internodes cells without a dolfinx match")
    return np.array([index[k] for k in keys])


# ---------------------------------------------------------------------------
# Checks of one body
# ---------------------------------------------------------------------------


def matrix_checks(model: ReferenceModel, out: InternodesOutput, body: Body, label: str) -> list[Check]:
    """Stiffness of the body and surface mass of each of its boundary groups."""
    n = out.body(body.name).summary["num_nodes"]
    checks = [Check("stiffness", f"{label} {body.name}",
                    relative_max(out.matrix(f"{body.name}_stiffness", (model.dim * n,) * 2), model.stiffness(body)),
                    TOLERANCES["stiffness"])]
    for group in body.boundary_groups():
        where = f"{label} {body.name}/{group}"
        ours = out.matrix(f"{body.name}__{group}_mass", (n, n))
        measure = model.group_measure(group)
        checks += [
            Check("surface mass", where, relative_max(ours, model.surface_mass(body.name, group)),
                  TOLERANCES["surface mass"]),
            Check("mass sum", where, abs(ours.sum() - measure) / measure, TOLERANCES["mass sum"],
                  f"|G| = {measure:.6g}"),
        ]
    return checks


def mesh_tag_check(model: ReferenceModel, out: InternodesOutput, body: Body, label: str) -> list[Check]:
    """Number of rows of the body's /mesh datasets inconsistent with the gmsh file (must be 0).

    A node row is wrong if its node_tag is not a gmsh node with exactly the
    row's coordinates, or if its node_body is not the body's index in
    summary.json; a cell row if its cell_tag is not an element of the body's
    physical group with the same nodes, or if its cell_body is wrong.
    Missing or extra cells count too.
    """
    ours = out.body(body.name)
    index = list(out.bodies).index(body.name)
    positions = model.node_positions
    known = (ours.node_tag > 0) & (ours.node_tag < len(positions))
    position = positions[np.where(known, ours.node_tag, 0)]
    bad_nodes = ~known | ~(position == ours.geometry).all(axis=1) | (ours.node_body != index)

    element_tags, element_nodes = model.body_elements[body.name]
    order = np.argsort(element_tags)
    row = order[np.clip(np.searchsorted(element_tags[order], ours.cell_tag), 0, len(order) - 1)]
    same_nodes = (np.sort(element_nodes[row], axis=1) == np.sort(ours.node_tag[ours.cells], axis=1)).all(axis=1)
    bad_cells = (element_tags[row] != ours.cell_tag) | ~same_nodes | (ours.cell_body != index)
    wrong = bad_nodes.sum() + bad_cells.sum() + abs(len(element_tags) - len(np.unique(ours.cell_tag)))
    return [Check("mesh tags", f"{label} {body.name}", wrong, 0,
                  f"{len(ours.node_tag)} nodes, {len(ours.cell_tag)} cells")]


def solution_checks(model: ReferenceModel, out: InternodesOutput, body: Body, label: str) -> list[Check]:
    """Displacements, reactions, strains, stresses and von Mises stress of the body."""
    ours = out.body(body.name)
    ref = model.solve(body)
    where = f"{label} {body.name}"
    u_ref = pad3(ref.displacement)
    order = cell_order(ours.cells, ref.cells, where)
    stress_ref = ref.stress[order]
    return [
        Check("displacement L2", where, relative_l2(ours.displacement, u_ref), TOLERANCES["displacement L2"],
              f"max|u| = {abs(u_ref).max():.3e}"),
        Check("displacement max", where, relative_max(ours.displacement, u_ref), TOLERANCES["displacement max"]),
        reaction_check(ours.summary.get("reactions", {}), ref.reactions, where),
        Check("strain", where, relative_max(ours.strain, ref.strain[order]), TOLERANCES["strain"]),
        Check("stress", where, relative_max(ours.stress, stress_ref), TOLERANCES["stress"],
              f"max|sigma| = {abs(stress_ref).max():.3e}"),
        Check("von Mises", where, relative_max(ours.von_mises, von_mises(stress_ref)), TOLERANCES["von Mises"]),
    ]


def reaction_check(ours: dict, reference: dict[str, np.ndarray], where: str, scale: float = 0.0) -> Check:
    """max |R - R_ref| / max(max |R_ref|, scale) over the Dirichlet groups of a body; ``scale``, the
    forces the body carries otherwise, for a body whose supports carry nothing but round-off."""
    if set(ours) != set(reference):
        return failure("reactions", where, f"groups {sorted(ours)} in summary.json, expected {sorted(reference)}")
    ours_all = np.concatenate([np.asarray(ours[g], dtype=float) for g in reference])
    ref_all = np.concatenate([reference[g] for g in reference])
    if ours_all.shape != ref_all.shape:
        return failure("reactions", where, f"{len(ours_all)} reaction components, expected {len(ref_all)}")
    figure = float(np.abs(ours_all - ref_all).max() / max(np.abs(ref_all).max(), scale))
    return Check("reactions", where, figure, TOLERANCES["reactions"], f"max|R| = {abs(ref_all).max():.3e}")


ERRORS = (MissingOutput, ReferenceFailure, OSError, KeyError, ValueError)


def compare_case(case: Case, output: Path, label: str) -> list[Check]:
    """All checks of one case: the internodes output folder against dolfinx.

    Missing / malformed output or an impossible reference gives a failed
    check naming the problem (for the whole case if the output or the mesh
    cannot be read, else for the group of checks concerned).
    """
    try:
        out = InternodesOutput(output)
        model = ReferenceModel(case.mesh, {b.name: out.body(b.name).geometry for b in case.bodies})
        if out.dim != model.dim:
            raise MissingOutput(f"{output}/summary.json: dimension {out.dim}, the mesh has dimension {model.dim}")
    except ERRORS as error:
        return [failure("comparison", label, f"{type(error).__name__}: {error}")]
    checks = []
    for body in case.bodies:
        for check_group in (mesh_tag_check, matrix_checks, solution_checks):
            try:
                checks += check_group(model, out, body, label)
            except ERRORS as error:
                checks.append(failure(check_group.__name__, f"{label} {body.name}",
                                      f"{type(error).__name__}: {error}"))
    return checks
