"""A half-disc pressed onto a block (2D, plane strain), built with the gmsh API and solved
without a mesh file: internodes reads gmsh's current model.

    python gmsh_in_memory.py [OUTPUT_FOLDER]     (writes the CLI's result files there)
"""

import sys
from pathlib import Path

import gmsh
import numpy as np

import internodes

E, NU, R = 1000.0, 0.3, 1.0


def build_half_disc_on_block(h_contact=0.01, h_far=0.3, width=2.0, height=2.0):
    """A half-disc of radius R whose lowest point touches the block's top at the origin; the
    two bodies share no node. Physical groups name the bodies and their boundaries."""
    geo = gmsh.model.geo
    point = lambda x, y, h: geo.addPoint(x, y, 0.0, h)  # noqa: E731
    # The disc: two arcs through the pole (0, 0), and its flat top at y = R.
    centre, left, pole, right = point(0, R, h_far), point(-R, R, h_far), point(0, 0, h_contact), point(R, R, h_far)
    arcs = [geo.addCircleArc(left, centre, pole), geo.addCircleArc(pole, centre, right)]
    top = geo.addLine(right, left)
    disc = geo.addPlaneSurface([geo.addCurveLoop(arcs + [top])])
    # The block [-W, W] x [-H, 0], with a point of its own under the pole.
    corners = [point(-width, -height, h_far), point(width, -height, h_far), point(width, 0, h_far),
               point(0, 0, h_contact), point(-width, 0, h_far)]
    sides = [geo.addLine(corners[k], corners[(k + 1) % 5]) for k in range(5)]
    block = geo.addPlaneSurface([geo.addCurveLoop(sides)])
    geo.synchronize()
    for dim, tags, name in [(2, [disc], "disc"), (2, [block], "block"), (1, arcs, "disc_contact"),
                            (1, [top], "disc_top"), (1, sides[2:4], "block_contact"),
                            (1, sides[:1], "block_base")]:
        gmsh.model.setPhysicalName(dim, gmsh.model.addPhysicalGroup(dim, tags), name)
    gmsh.model.mesh.generate(2)


def case(approach=0.02):
    """The disc's top pushed down by `approach` and held laterally; the block's base clamped."""
    body = lambda name, group, uy: {  # noqa: E731
        "name": name, "youngs_modulus": E, "poisson_ratio": NU,
        "dirichlet": [{"group": group, "ux": 0.0, "uy": uy}],
    }
    return internodes.Case.from_dict({
        "contact": {"bodies": ["disc", "block"], "surfaces": ["disc_contact", "block_contact"]},
        "body": [body("disc", "disc_top", -approach), body("block", "block_base", 0.0)],
    }, name="half_disc_in_memory")


def main(output):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        build_half_disc_on_block()
        mesh = internodes.Mesh.from_gmsh()  # no file: the current model's nodes and elements
    finally:
        gmsh.finalize()
    result = internodes.solve(case(), mesh=mesh)
    result.raise_for_status()
    contact = result.summary["contact"]
    force = np.linalg.norm(contact["force_primary"])  # per unit thickness
    # Plane-strain Hertz half-width for two equal bodies: a = sqrt(4 F R / (pi E*)).
    e_star = E / (2 * (1 - NU**2))
    print(f"{mesh}\nstatus {result.status}, force {force:.6e}, "
          f"half-width {contact['hertz_fit']['a']:.4e} (Hertz at this force "
          f"{np.sqrt(4 * force * R / (np.pi * e_star)):.4e})")
    disc = result.bodies["disc"]
    print(f"largest pressure {disc.surface.pressure.max():.4e} on {disc.surface.active.sum()} "
          f"active nodes; largest von Mises stress in the disc {disc.von_mises.max():.4e}")
    # The example's own folder: a second run replaces the first one's results.
    result.write(output, overwrite=True)


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "gmsh_in_memory"))
