#!/usr/bin/env python3
"""The picture of the README: the demo's answer read back from its output files.

Left, the von Mises stress on the section y = 0 of the deformed hemisphere and block
(displacements magnified), each tetrahedron cut by the plane; right, the contact pressure of
every node of the two contact surfaces against its distance from the centre of the contact
zone, with the Hertz profile ``p0 sqrt(1 - r^2 / a^2)`` fitted by the solver (summary.json).

    make demo && /usr/bin/python3 validation/render_demo.py            # writes docs/demo.png
    /usr/bin/python3 validation/render_demo.py --output-dir out/x --png x.png

Reads ``solution.h5`` (the layout of ``docs/output.md``) and ``summary.json`` only: what a
user's own script would read. Needs Debian's python3-h5py and python3-matplotlib.
"""

import argparse
import json
from pathlib import Path

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

REPO = Path(__file__).resolve().parent.parent

#: Displacements are drawn this many times larger (the approach is 1% of the radius).
MAGNIFY = 10.0
#: The window of the section around the contact zone (x, z), in units of the sphere's radius.
WINDOW = ((-0.4, 0.4), (-0.3, 0.25))


def section(points: np.ndarray, cells: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """The polygons (x, z) in which the plane y = 0 cuts each tetrahedron of ``cells`` (vertex
    coordinates ``points``), and the indices of the cut cells."""
    y = points[cells, 1]
    cut = np.nonzero((y.min(axis=1) < 0.0) & (y.max(axis=1) > 0.0))[0]
    polygons = []
    for c in cut:
        corners = points[cells[c]]
        found = []
        for i in range(4):
            for j in range(i + 1, 4):
                yi, yj = corners[i, 1], corners[j, 1]
                if (yi < 0.0) != (yj < 0.0):
                    t = yi / (yi - yj)
                    p = corners[i] + t * (corners[j] - corners[i])
                    found.append((p[0], p[2]))
        polygon = np.array(found)
        centre = polygon.mean(axis=0)
        order = np.argsort(np.arctan2(polygon[:, 1] - centre[1], polygon[:, 0] - centre[0]))
        polygons.append(polygon[order])
    return polygons, cut


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--output-dir", type=Path, default=REPO / "out" / "demo",
                        help="the demo's output folder (default: out/demo, written by `make demo`)")
    parser.add_argument("--png", type=Path, default=REPO / "docs" / "demo.png", help="the picture to write")
    args = parser.parse_args()

    summary = json.loads((args.output_dir / "summary.json").read_text())
    contact = summary["contact"]
    fit = contact["hertz_fit"]
    with h5py.File(args.output_dir / "solution.h5", "r") as h5:
        points = h5["mesh/geometry"][:]
        cells = h5["mesh/topology"][:]
        node_body = h5["mesh/node_body"][:]
        displacement = h5["fields/displacement"][:]
        von_mises = h5["fields/von_mises"][:]
        pressure = h5["fields/contact_pressure"][:]
        gap = h5["fields/normal_gap"][:]

    figure, (left, right) = plt.subplots(1, 2, figsize=(12, 5.2), gridspec_kw={"width_ratios": [1.15, 1]})
    deformed = points + MAGNIFY * displacement
    polygons, cut = section(deformed, cells)
    shapes = PolyCollection(polygons, array=von_mises[cut], cmap="viridis", edgecolors="0.25", linewidths=0.08)
    left.add_collection(shapes)
    left.set_xlim(*WINDOW[0])
    left.set_ylim(*WINDOW[1])
    left.set_aspect("equal")
    left.set_xlabel("x")
    left.set_ylabel("z")
    left.set_title(f"von Mises stress on the section y = 0 (displacements x{MAGNIFY:g})", fontsize=11)
    figure.colorbar(shapes, ax=left, shrink=0.85, label="von Mises stress")

    # The nodes of the candidate surfaces carry a normal gap; every other node has NaN.
    centre = np.array(fit["center"])
    radius = np.linalg.norm(points[:, :2] - centre[:2], axis=1)
    on_surface = np.isfinite(gap)
    bodies = contact["primary"], contact["secondary"]
    names = [b["name"] for b in summary["bodies"]]  # in the order of mesh/node_body
    for body, marker in zip(bodies, ("o", "x")):
        nodes = on_surface & (node_body == names.index(body)) & (radius < 2.0 * fit["a"])
        right.plot(radius[nodes], pressure[nodes], marker, ms=3.5, alpha=0.7, mfc="none" if marker == "o" else None,
                   label=f"'{body}' nodes ({'primary' if body == bodies[0] else 'secondary'})")
    r = np.linspace(0.0, fit["a"], 200)
    right.plot(r, fit["p0"] * np.sqrt(1.0 - (r / fit["a"]) ** 2), "k-", lw=1.5,
               label=f"Hertz fit: a = {fit['a']:.4f}, p0 = {fit['p0']:.2f}")
    right.set_xlim(0.0, 2.0 * fit["a"])
    right.set_xlabel("distance r from the centre of the contact zone")
    right.set_ylabel("contact pressure")
    right.set_title(f"contact pressure; total force {np.linalg.norm(contact['force_primary']):.4f}", fontsize=11)
    right.legend(fontsize=9)
    right.grid(alpha=0.3)
    figure.suptitle(f"make demo: hemisphere (R = 1) pressed by 0.01 onto a block, {contact['status']} "
                    f"({summary['case']})", fontsize=12)
    figure.tight_layout()
    args.png.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(args.png, dpi=100)
    print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
