"""Reads a gmsh model's mesh through the gmsh Python API, for ``Mesh.from_gmsh``.

Only gathers arrays: the checks and the split into bodies are the solver's own, the same as for
a file.
"""

import numpy as np

from ._internodes import InputError


def _initialized(gmsh):
    """Whether gmsh is initialized. gmsh 4.8 (Debian 12) has no ``isInitialized``; an initialized
    gmsh has a model (at least the unnamed one), an uninitialized one lists none."""
    if hasattr(gmsh, "isInitialized"):
        return bool(gmsh.isInitialized())
    try:
        return bool(gmsh.model.list())
    except Exception:  # after gmsh.finalize(), gmsh 4.8 fails to fetch its own error
        return False


def model_arrays(model=None):
    """The physical groups, nodes and element blocks of gmsh's current model (or ``model``)."""
    import gmsh

    # gmsh's API answers an uninitialized gmsh with an empty model, read as a mesh without
    # bodies: say what is wrong instead.
    if not _initialized(gmsh):
        raise InputError(
            "gmsh is not initialized: call gmsh.initialize(), build and mesh a model, then "
            "Mesh.from_gmsh() before gmsh.finalize()"
        )
    try:
        if model is not None:
            gmsh.model.setCurrent(model)
        name = gmsh.model.getCurrent()
    except Exception as error:
        raise InputError(
            f"no gmsh model to read ({error}): call gmsh.initialize(), build and mesh a model, "
            "then Mesh.from_gmsh() before gmsh.finalize()"
        ) from error
    groups = []
    for dim, tag in gmsh.model.getPhysicalGroups():
        entities = [int(e) for e in gmsh.model.getEntitiesForPhysicalGroup(dim, tag)]
        groups.append((int(dim), int(tag), gmsh.model.getPhysicalName(dim, tag), entities))
    node_tags, coords, _ = gmsh.model.mesh.getNodes()
    blocks = []
    for dim, entity in gmsh.model.getEntities():
        types, element_tags, element_nodes = gmsh.model.mesh.getElements(dim, entity)
        for kind, tags, nodes in zip(types, element_tags, element_nodes):
            blocks.append(
                (
                    int(dim),
                    int(entity),
                    int(kind),
                    np.ascontiguousarray(tags, dtype=np.uint64),
                    np.ascontiguousarray(nodes, dtype=np.uint64),
                )
            )
    return {
        "label": f"gmsh model '{name}'" if name else "gmsh model",
        "groups": groups,
        "num_volumes": len(gmsh.model.getEntities(3)),
        "node_tags": np.ascontiguousarray(node_tags, dtype=np.uint64),
        "coords": np.ascontiguousarray(coords, dtype=np.float64),
        "blocks": blocks,
    }
