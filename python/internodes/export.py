"""A result's meshes and fields as meshio objects, without writing files (``to_meshio``)."""

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import meshio as _meshio

    from ._internodes import Result as _Result

# meshio's names of the P1 cells.
CELL_TYPES = {2: "triangle", 3: "tetra"}


def to_meshio(result: "_Result") -> "dict[str, _meshio.Mesh]":
    """Each body's mesh and fields as a ``meshio.Mesh``, by body name: the fields
    ``solution.xdmf`` holds. Point data: ``displacement``, and in contact runs the contact
    fields on the candidate surfaces (zero at other nodes, as in the XDMF file):
    ``contact_pressure``, ``contact_mean_pressure``, ``contact_traction``, ``normal_gap``,
    ``contact_active``. Cell data: ``strain`` and ``stress`` (3 x 3 per cell) and
    ``von_mises``. Needs the ``meshio`` package (Debian: python3-meshio)."""
    import meshio

    meshes = {}
    for name, body in result.bodies.items():
        dim = body.coordinates.shape[1]
        points = body.coordinates
        point_data = {"displacement": body.displacement}
        # A body in several pairs has a surface in each, written in the case's order of pairs
        # (as solution.xdmf: a node on two surfaces holds the later pair's values).
        for surface in body.surfaces.values():
            nodes = surface.nodes.astype(np.intp)
            for key, values in [("contact_pressure", surface.pressure),
                                ("contact_mean_pressure", surface.mean_pressure),
                                ("contact_traction", surface.traction),
                                ("normal_gap", surface.gap),
                                ("contact_active", surface.active.astype(np.float64))]:
                full = point_data.setdefault(key, np.zeros((len(points),) + values.shape[1:]))
                full[nodes] = values
        cells = [(CELL_TYPES[dim], body.cells.astype(np.int64))]
        cell_data = {"strain": [body.strain], "stress": [body.stress], "von_mises": [body.von_mises]}
        meshes[name] = meshio.Mesh(points, cells, point_data=point_data, cell_data=cell_data)
    return meshes
