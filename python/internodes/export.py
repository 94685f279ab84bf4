"""A result's meshes and fields as meshio objects, without writing files (``to_meshio``)."""

from typing import TYPE_CHECKING, Optional

import numpy as np

if TYPE_CHECKING:
    import meshio as _meshio

    from ._internodes import Result as _Result

# meshio's names of the P1 cells.
CELL_TYPES = {2: "triangle", 3: "tetra"}


def to_meshio(result: "_Result", step: Optional[int] = None) -> "dict[str, _meshio.Mesh]":
    """Each body's mesh and fields as a ``meshio.Mesh``, by body name: the fields
    ``solution.xdmf`` holds, at the last load step, or at load step ``step + 1`` (the index of
    ``result.steps``, as ``result.step_bodies(step)``). Point data: ``displacement``, and in
    contact runs the contact fields on the candidate surfaces (zero at other nodes, as in the
    XDMF file): ``contact_pressure``, ``contact_mean_pressure``, ``contact_traction``,
    ``normal_gap``, ``contact_active``. Cell data: ``strain`` and ``stress``, each cell's 3 x 3
    tensor flattened row by row into 9 components (``xx, xy, xz, yx, yy, yz, zx, zy, zz``; an
    ``(m, 9)`` array), and ``von_mises``. Needs the ``meshio`` package (Debian:
    python3-meshio)."""
    import meshio

    bodies = result.bodies if step is None else result.step_bodies(step)
    meshes = {}
    for name, body in bodies.items():
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
        # Tensors as 9 components per cell: meshio's VTU writer keeps only the first axis of an
        # (m, 3, 3) array (the values read back as (m,)) and its legacy VTK writer writes a file
        # it cannot read, while every writer keeps an (m, 9) array, which ParaView reads as a
        # tensor.
        cell_data = {"strain": [body.strain.reshape(-1, 9)],
                     "stress": [body.stress.reshape(-1, 9)],
                     "von_mises": [body.von_mises]}
        meshes[name] = meshio.Mesh(points, cells, point_data=point_data, cell_data=cell_data)
    return meshes
