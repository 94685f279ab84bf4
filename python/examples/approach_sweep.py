"""Approach sweep: an elastic hemisphere (R = 1) pressed onto an elastic block by ten approaches.

Plots the contact force against the imposed approach, and the contact radius against the force
with Hertz's curve a = (3 F R / (4 E*))^(1/3). Hertz is drawn against the force rather than the
approach: the imposed approach also compresses the finite bodies, which Hertz's approach of
distant points leaves out, while a(F) holds whatever the bodies' size.

    python approach_sweep.py [OUTPUT_FOLDER]     (writes approach_sweep.png and .csv)
"""

import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import internodes

GEO = Path(__file__).resolve().parents[2] / "geo" / "hemisphere_on_block.geo"
E, NU, R = 1000.0, 0.3, 1.0


def case(approach):
    """The hemisphere's flat top pushed down by `approach`; the block's base clamped."""
    body = lambda name, group, uz: {  # noqa: E731
        "name": name, "youngs_modulus": E, "poisson_ratio": NU,
        "dirichlet": [{"group": group, "ux": 0.0, "uy": 0.0, "uz": uz}],
    }
    return internodes.Case.from_dict({
        "contact": {"bodies": ["sphere", "block"], "surfaces": ["sphere_contact", "block_contact"]},
        "body": [body("sphere", "sphere_top", -approach), body("block", "block_base", 0.0)],
    }, name=f"approach {approach:g}")


def main(output):
    # 1. One mesh for every solve: refined to R/67 where the contact zone grows.
    mesh = internodes.Mesh.from_geo(GEO, {"h_c": 0.015, "r_c": 0.16, "h_far": 0.5, "d_far": 1.0})

    # 2. Ten solves; each result's summary is the CLI's summary.json as a dict.
    approaches = np.linspace(0.002, 0.02, 10)
    forces, radii = [], []
    for approach in approaches:
        result = internodes.solve(case(approach), mesh=mesh)
        result.raise_for_status()
        contact = result.summary["contact"]
        forces.append(np.linalg.norm(contact["force_primary"]))
        radii.append(contact["hertz_fit"]["a"])

    # 3. Hertz, for two equal bodies: 1 / E* = 2 (1 - nu^2) / E.
    e_star = E / (2 * (1 - NU**2))
    f = np.linspace(0, max(forces), 100)
    figure, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    left.plot(approaches, forces, "o-")
    left.set(xlabel="imposed approach", ylabel="contact force |F|", xlim=(0, None), ylim=(0, None))
    right.plot(forces, radii, "o", label="internodes (Hertz fit of the pressure)")
    right.plot(f, (3 * f * R / (4 * e_star)) ** (1 / 3), "-", label="Hertz")
    right.set(xlabel="contact force |F|", ylabel="contact radius a", xlim=(0, None), ylim=(0, None))
    right.legend()
    output.mkdir(parents=True, exist_ok=True)
    figure.savefig(output / "approach_sweep.png", dpi=120, bbox_inches="tight")
    np.savetxt(output / "approach_sweep.csv", np.column_stack([approaches, forces, radii]),
               delimiter=",", header="approach,force,contact_radius", comments="")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "approach_sweep"))
