#!/usr/bin/python3
"""Foreign meshes: the contact solver on meshes that owe nothing to ``geo/``.

Every other suite meshes the ``geo/`` scripts, whose contact point is always a mesh node of both
bodies and whose size fields all grow from it. A user's mesh is not made that way. This check
builds the half-disc (2D) and hemisphere (3D) on a block with gmsh's OpenCASCADE kernel and the
Python API: boolean-cut bodies whose pole and whose block-top origin are *not* mesh nodes (the
curved body is also shifted sideways by a fraction of a spacing), boundary facets in whatever
orientation OpenCASCADE gives them, and one of three size fields:

* ``box``: a Box field (fine inside a square/cube around the contact point, a linear transition);
* ``distance``: each body refined by its distance to the *other* body's contact surface (a band
  along the whole interface, as a user refining "where the bodies are close" would do);
* ``matheval``: a MathEval size growing linearly with the distance from a point off the axis.

Each mesh is solved by internodes (curved body E = 1000, block 1e4 times stiffer; ``primary`` auto
and each body explicitly) and compared with two measures that do not reuse the solver:

1. the force on the curved body against dolfinx's rigid flat on the same curved mesh
   (``contact_reference.py``, an exact node-to-plane constraint), tolerance 1%;
2. the geometric penetration, recomputed here from ``solution.h5``: every contact-surface node of
   each body, displaced, against the other body's displaced contact facets (closest point,
   signed by the known outward direction of the facet: up for the block top, away from the
   centre for the curved body). Reported in units of the local spacing.

Verdict per run: ``right`` (vouched for by the solver: converged with a passing accuracy report;
force within 1%, neither body's nodes penetrating the other by more than the solver's residual
checks allow: 1e-3 h for the primary's nodes, 5e-2 h for the secondary's), ``named`` (a status
other than converged, or a failed accuracy indicator; its force error is listed for information),
``WRONG`` (vouched for, and off on force or penetration). Exits 1 if any run is
WRONG or fails to run.

Not part of ``make validate`` (several minutes). Writes ``validation/report/foreign_meshes.md``.

Usage:  /usr/bin/python3 validation/foreign_meshes.py [--binary PATH] [--only SUBSTRING]
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

VALIDATION = Path(__file__).resolve().parent

import contact_reference  # noqa: E402
import rigid_flat  # noqa: E402
from suite import failed_report_names, run_solve, vouched  # noqa: E402

BUILD = VALIDATION / "build" / "foreign_meshes"
REPORT = VALIDATION / "report" / "foreign_meshes.md"
FORCE_TOLERANCE = 0.01
# The residual checks' penetration bounds (ContactSettings defaults): primary nodes, secondary nodes, in h.
PRIMARY_PENETRATION = 1e-3
SECONDARY_PENETRATION = 0.05
RADIUS, HALF_WIDTH, HEIGHT = 1.0, 2.0, 2.0
CURVED = {2: "disc", 3: "sphere"}


@dataclass(frozen=True)
class Mesh:
    """One foreign mesh: dimension, size field, contact spacing, block/curved spacing ratio,
    lateral shift of the curved body (in h_c), initial gap (negative: meshed overlapping),
    gmsh 2D algorithm."""

    dim: int
    field: str
    h_c: float
    block_ratio: float
    shift: float
    gap: float = 0.0
    algorithm: int = 6

    @property
    def name(self) -> str:
        return (f"{self.dim}d_{self.field}_R{1 / self.h_c:.0f}_b{self.block_ratio:g}_s{self.shift:g}"
                f"_g{self.gap:g}_a{self.algorithm}")


def build_mesh(m: Mesh, r_c: float, path: Path) -> Path:
    """Mesh ``m`` with the OpenCASCADE kernel into ``path`` (MSH 4.1, only physical groups)."""
    import gmsh

    if path.is_file():
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(m.name)
        occ = gmsh.model.occ
        R, W, H, d = RADIUS, HALF_WIDTH, HEIGHT, m.dim
        x0 = m.shift * m.h_c  # the pole's lateral position: not a node of either mesh
        if d == 2:
            block = occ.addRectangle(-W, -H, 0, 2 * W, H)
            disc = occ.addDisk(x0, R + m.gap, 0, R, R)
            cap = occ.addRectangle(x0 - 2 * R, R + m.gap, 0, 4 * R, 2 * R)
            curved = occ.cut([(2, disc)], [(2, cap)])[0][0][1]
        else:
            block = occ.addBox(-W, -W, -H, 2 * W, 2 * W, H)
            ball = occ.addSphere(x0, 0.3 * x0, R + m.gap, R)
            cap = occ.addBox(x0 - 2 * R, -2 * R, R + m.gap, 4 * R, 4 * R, 2 * R)
            curved = occ.cut([(3, ball)], [(3, cap)])[0][0][1]
        occ.synchronize()
        boundary = lambda tag: [b[1] for b in gmsh.model.getBoundary([(d, tag)], oriented=False)]
        top_of = lambda tag: gmsh.model.getBoundingBox(d - 1, tag)
        v = d - 1  # vertical axis index in a bounding box (xmin, ymin, zmin, xmax, ymax, zmax)
        curved_faces = boundary(curved)
        flat = [t for t in curved_faces if abs(top_of(t)[v] - (R + m.gap)) < 1e-6]
        contact = [t for t in curved_faces if t not in flat]
        block_faces = boundary(block)
        block_top = [t for t in block_faces if abs(top_of(t)[v]) < 1e-6 and abs(top_of(t)[v + 3]) < 1e-6]
        block_base = [t for t in block_faces if abs(top_of(t)[v + 3] + H) < 1e-6]
        groups = {"curved": (d, [curved]), "block": (d, [block]),
                  "curved_top": (d - 1, flat), "curved_contact": (d - 1, contact),
                  "block_contact": (d - 1, block_top), "block_base": (d - 1, block_base)}
        for key, (dimension, tags) in groups.items():
            name = key.replace("curved", CURVED[d])
            gmsh.model.setPhysicalName(dimension, gmsh.model.addPhysicalGroup(dimension, tags), name)

        fields = []
        for body, ratio in ((curved, 1.0), (block, m.block_ratio)):
            h, h_far = m.h_c * ratio, 0.4
            f = gmsh.model.mesh.field
            if m.field == "box":
                size = f.add("Box")
                f.setNumber(size, "VIn", h)
                f.setNumber(size, "VOut", h_far)
                for axis, c in zip("XYZ", (x0, 0.0, 0.0)):
                    f.setNumber(size, f"{axis}Min", c - r_c)
                    f.setNumber(size, f"{axis}Max", c + r_c)
                f.setNumber(size, "Thickness", 4 * r_c)
            elif m.field == "distance":
                distance = f.add("Distance")
                other = block_top if body == curved else contact
                f.setNumbers(distance, "CurvesList" if d == 2 else "SurfacesList", other)
                f.setNumber(distance, "NumPointsPerCurve", 400 if d == 2 else 100)
                size = f.add("Threshold")
                f.setNumber(size, "InField", distance)
                f.setNumber(size, "SizeMin", h)
                f.setNumber(size, "SizeMax", h_far)
                f.setNumber(size, "DistMin", r_c * r_c / (2 * R))
                f.setNumber(size, "DistMax", 1.0)
            elif m.field == "matheval":
                size = f.add("MathEval")
                centre = f"Sqrt((x-({x0 + 0.25 * r_c}))^2 + y^2" + ("+ z^2)" if d == 3 else ")")
                f.setString(size, "F", f"Min({h_far}, {h} + 0.3 * Max(0, {centre} - {r_c}))")
            else:
                raise ValueError(m.field)
            restricted = f.add("Restrict")
            f.setNumber(restricted, "InField", size)
            # the restriction must list every entity of the body down to its curves, or gmsh
            # meshes the curves left out with one segment each
            faces = gmsh.model.getBoundary([(d, body)], oriented=False)
            curves = gmsh.model.getBoundary(faces, combined=False, oriented=False) if d == 3 else faces
            f.setNumbers(restricted, "SurfacesList" if d == 2 else "VolumesList", [body])
            if d == 3:
                f.setNumbers(restricted, "SurfacesList", [t for _, t in faces])
            f.setNumbers(restricted, "CurvesList", sorted({t for _, t in curves}))
            fields.append(restricted)
        smallest = gmsh.model.mesh.field.add("Min")
        gmsh.model.mesh.field.setNumbers(smallest, "FieldsList", fields)
        gmsh.model.mesh.field.setAsBackgroundMesh(smallest)
        for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
            gmsh.option.setNumber(f"Mesh.{option}", 0)
        gmsh.option.setNumber("Mesh.Algorithm", m.algorithm)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.model.mesh.generate(d)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path


# ---------------------------------------------------------------------------
# Independent penetration measure (reads solution.h5 and the .msh; owes nothing to the solver)
# ---------------------------------------------------------------------------


def surface_facets(msh: Path, group: str) -> np.ndarray:
    """gmsh node tags of the facets of a physical group, one row per facet."""
    import gmsh

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(msh))
        dim = gmsh.model.getDimension() - 1
        tag = next(t for d, t in gmsh.model.getPhysicalGroups(dim) if gmsh.model.getPhysicalName(d, t) == group)
        rows = []
        for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
            _, _, nodes = gmsh.model.mesh.getElements(dim, entity)
            rows.append(np.asarray(nodes[0], dtype=np.int64).reshape(-1, dim + 1))
        return np.concatenate(rows)
    finally:
        gmsh.finalize()


def closest_points(points: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """Closest point of each point (p, 3) on each of its candidate facets (p, k, n, 3), n = 2 or 3:
    returns (p, k, 3). Segments: clamped projection. Triangles: Ericson's region tests."""
    p = points[:, None, :]
    if facets.shape[2] == 2:
        a, b = facets[:, :, 0], facets[:, :, 1]
        t = np.clip(((p - a) * (b - a)).sum(-1) / ((b - a) ** 2).sum(-1), 0.0, 1.0)
        return a + t[..., None] * (b - a)
    a, b, c = facets[:, :, 0], facets[:, :, 1], facets[:, :, 2]
    dot = lambda u, w: (u * w).sum(-1)
    ab, ac, ap, bp, cp = b - a, c - a, p - a, p - b, p - c
    d1, d2, d3, d4, d5, d6 = dot(ab, ap), dot(ac, ap), dot(ab, bp), dot(ac, bp), dot(ab, cp), dot(ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denominator = va + vb + vc
        v, w = vb / denominator, vc / denominator
        result = a + v[..., None] * ab + w[..., None] * ac  # interior
        edge_bc = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        result = np.where(edge_bc[..., None], b + t[..., None] * (c - b), result)
        edge_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
        result = np.where(edge_ac[..., None], a + (d2 / (d2 - d6))[..., None] * ac, result)
        edge_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
        result = np.where(edge_ab[..., None], a + (d1 / (d1 - d3))[..., None] * ab, result)
    result = np.where(((d6 >= 0) & (d5 <= d6))[..., None], c, result)
    result = np.where(((d3 >= 0) & (d4 <= d3))[..., None], b, result)
    result = np.where(((d1 <= 0) & (d2 <= 0))[..., None], a, result)
    return result


def signed_gaps(points: np.ndarray, facet_x: np.ndarray, outward: np.ndarray) -> np.ndarray:
    """Signed distance of each point to the facet surface (facet_x (f, n, 3), outward unit facet
    normals (f, 3)): the distance to the closest point, negative when the point lies behind the
    closest facet's outward normal."""
    from scipy.spatial import cKDTree

    centroids = facet_x.mean(axis=1)
    k = min(32, len(facet_x))
    _, candidates = cKDTree(centroids).query(points, k=k)
    candidates = candidates.reshape(len(points), k)
    closest = closest_points(points, facet_x[candidates])
    distance = np.linalg.norm(points[:, None, :] - closest, axis=-1)
    best = distance.argmin(axis=1)
    rows = np.arange(len(points))
    offset = points - closest[rows, best]
    side = np.sign((offset * outward[candidates[rows, best]]).sum(-1))
    return np.where(side < 0, -distance[rows, best], distance[rows, best])


def facet_normals(x: np.ndarray) -> np.ndarray:
    """Unit normals (any orientation) of segments in the xy plane or of triangles."""
    if x.shape[1] == 2:
        t = x[:, 1] - x[:, 0]
        n = np.stack([t[:, 1], -t[:, 0], np.zeros(len(t))], axis=1)
    else:
        n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def penetration(m: Mesh, msh: Path, folder: Path) -> dict:
    """Largest penetration (over the node's spacing) of each body's contact nodes into the other
    body's displaced contact surface, from solution.h5."""
    import h5py
    from scipy.spatial import cKDTree

    summary = json.loads((folder / "summary.json").read_text())
    with h5py.File(folder / "solution.h5", "r") as h5:
        x_all, tags_all, u_all = h5["mesh/geometry"][:], h5["mesh/node_tag"][:], h5["fields/displacement"][:]
    curved = CURVED[m.dim]
    bodies = {}
    for b in summary["bodies"]:
        rows = slice(b["node_offset"], b["node_offset"] + b["num_nodes"])
        row_of = {int(t): k for k, t in enumerate(tags_all[rows])}
        facets = surface_facets(msh, f"{b['name']}_contact")
        local = np.vectorize(row_of.__getitem__)(facets)
        x, u = x_all[rows], u_all[rows]
        nodes = np.unique(local)
        spacing = cKDTree(x[nodes]).query(x[nodes], k=2)[0][:, 1]
        n = facet_normals(x[local] + u[local])
        if b["name"] == "block":
            n *= np.sign(n[:, m.dim - 1])[:, None]  # the block's top: outward is up
        else:
            centre = np.zeros(3)
            centre[0], centre[m.dim - 1] = m.shift * m.h_c, RADIUS + m.gap
            if m.dim == 3:
                centre[1] = 0.3 * m.shift * m.h_c
            n *= np.sign(((x[local].mean(axis=1) - centre) * n).sum(-1))[:, None]
        bodies[b["name"]] = {"deformed": (x + u)[nodes], "spacing": spacing, "facets": (x + u)[local],
                             "normals": n, "tags": tags_all[rows][nodes]}
    result = {}
    for name, other in ((curved, "block"), ("block", curved)):
        me, you = bodies[name], bodies[other]
        gaps = signed_gaps(me["deformed"], you["facets"], you["normals"]) / me["spacing"]
        worst = int(gaps.argmin())
        result[name] = {"max_penetration_over_h": float(max(0.0, -gaps[worst])), "node_tag": int(me["tags"][worst])}
    return result


# ---------------------------------------------------------------------------
# Runs
# ---------------------------------------------------------------------------


def lifted(msh: Path, lift: float, dim: int) -> Path:
    """The mesh translated by ``lift`` along the vertical axis (the same discrete bodies)."""
    import gmsh

    if lift == 0:
        return msh
    out = msh.with_name(f"{msh.stem}_lifted.msh")
    if out.is_file():
        return out
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(msh))
        tags, coords, _ = gmsh.model.mesh.getNodes(includeBoundary=True, returnParametricCoord=False)
        for k, tag in enumerate(tags):
            x = list(coords[3 * k:3 * k + 3])
            x[dim - 1] += lift
            gmsh.model.mesh.setNode(int(tag), x, [])
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.write(str(out))
    finally:
        gmsh.finalize()
    return out


def case_text(m: Mesh, msh: Path, primary: str, approach: float, output: Path) -> str:
    """rigid_flat's case (curved body on a block 1e4 times stiffer), with our primary and the top
    displacement that brings the total approach (initial overlap included) to ``approach``."""
    top = float(f"{approach + m.gap:.12g}")
    return rigid_flat.case_text(msh, m.dim, primary, output, 1.0, top, listed_first=CURVED[m.dim])


def run(binary: Path, m: Mesh, approach: float, primaries: tuple[str, ...]) -> list[dict]:
    """One mesh, one approach: the reference once, internodes once per primary choice."""
    r_c = 1.5 * math.sqrt(2 * approach) if m.dim == 3 else 1.8 * math.sqrt(approach)
    msh = build_mesh(m, max(r_c, 4 * m.h_c), BUILD / "meshes" / f"{m.name}.msh")
    stem = f"{m.name}_d{approach:g}"
    reference_json = BUILD / "references" / stem / "contact_reference.json"
    if reference_json.is_file():
        reference = json.loads(reference_json.read_text())
    else:
        # the reference wants the body above its flat: an overlapping mesh is lifted out of it
        reference = contact_reference.run_reference(lifted(msh, -m.gap, m.dim), reference_json.parent,
                                                    delta=approach, fractions=(1.0,), kappas=())
    rows = []
    for primary in primaries:
        output = BUILD / "runs" / f"{stem}_{primary}"
        case = output.parent / f"{output.name}.toml"
        case.parent.mkdir(parents=True, exist_ok=True)
        case.write_text(case_text(m, msh, primary, approach, output))
        done = run_solve(binary, case, output)
        row = {"mesh": m.name, "dim": m.dim, "field": m.field, "h_c": f"R/{1 / m.h_c:.0f}",
               "block_ratio": m.block_ratio, "gap": m.gap, "approach": approach, "asked": primary}
        summary_path = output / "summary.json"
        if not summary_path.is_file():
            row.update(verdict="FAILED TO RUN", message=done.log.strip().splitlines()[-1:])
            rows.append(row)
            continue
        contact = json.loads(summary_path.read_text())["contact"]
        force_key = "force_primary" if contact["primary"] == CURVED[m.dim] else "force_secondary"
        force = contact[force_key][m.dim - 1]
        force_error = force / reference["solution"]["force"] - 1
        pen = penetration(m, msh, output)
        primary_body = contact["primary"]
        secondary_body = "block" if primary_body == CURVED[m.dim] else CURVED[m.dim]
        failed = failed_report_names(contact)
        row.update(status=contact["status"], primary=primary_body, iterations=len(contact["iterations"]),
                   force_error=force_error, failed_checks=failed,
                   primary_penetration=pen[primary_body]["max_penetration_over_h"],
                   secondary_penetration=pen[secondary_body]["max_penetration_over_h"])
        wrong = (abs(force_error) > FORCE_TOLERANCE or row["primary_penetration"] > PRIMARY_PENETRATION
                 or row["secondary_penetration"] > SECONDARY_PENETRATION)
        if vouched(contact):
            row["verdict"] = "WRONG" if wrong else "right"
        else:
            row["verdict"] = "named"
        rows.append(row)
    return rows


def cases(dim: int) -> list[tuple[Mesh, float]]:
    """The grid: every size field at three spacings (2D) or two (3D), three block ratios, two
    approaches, and each mesh also meshed overlapping by half the approach. The 2D mesh
    algorithm varies with the field (Frontal-Delaunay, Delaunay, MeshAdapt)."""
    if dim == 2:
        spacings, approaches = (1 / 30, 1 / 150, 1 / 600), (0.003, 0.03)
        ratios = (0.5, 1.0, 2.5)
    else:
        spacings, approaches = (1 / 25, 1 / 45), (0.004, 0.012)
        ratios = (0.5, 1.0, 2.0)
    algorithms = {"box": 6, "distance": 5, "matheval": 1}
    grid = []
    for field, h_c, ratio, approach in itertools.product(algorithms, spacings, ratios, approaches):
        for gap in (0.0, -0.5 * approach):
            grid.append((Mesh(dim, field, h_c, ratio, 0.37, gap, algorithms[field] if dim == 2 else 6), approach))
    return grid


def report(rows: list[dict], commit: str) -> str:
    """The Markdown table of every run and the tally."""
    verdicts = [r["verdict"] for r in rows]
    lines = [
        "# Foreign meshes: the contact solver on meshes made without `geo/`",
        "",
        f"Written by `validation/foreign_meshes.py` at commit {commit}; do not edit by hand. Meshes built "
        "with gmsh's OpenCASCADE kernel (pole and origin not mesh nodes, the curved body shifted 0.37 h "
        "sideways, Box / Distance-to-the-other-body / MathEval size fields); curved body E = 1000 on a "
        "block 1e4 times stiffer; force against dolfinx's rigid flat on the same curved mesh (1%), "
        "penetration recomputed from `solution.h5` by closest point on the other body's displaced "
        f"facets (primary nodes {PRIMARY_PENETRATION:g} h, secondary nodes {SECONDARY_PENETRATION:g} h).",
        "",
        f"**{len(rows)} runs: {verdicts.count('right')} vouched for and right, {verdicts.count('named')} ended "
        f"with a named status or a failed accuracy indicator, {verdicts.count('WRONG')} vouched for and wrong, "
        f"{verdicts.count('FAILED TO RUN')} failed to run.**",
        "",
        "| mesh | approach | asked | primary | verdict | status | iterations | force error | "
        "primary pen. / h | secondary pen. / h | failed checks |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    pct = lambda v: f"{100 * v:+.2f}%" if isinstance(v, float) else "-"
    num = lambda v: f"{v:.1e}" if isinstance(v, float) else "-"
    for r in rows:
        lines.append(f"| {r['mesh']} | {r['approach']:g} | {r['asked']} | {r.get('primary', '-')} | {r['verdict']} "
                     f"| {r.get('status', '-')} | {r.get('iterations', '-')} | {pct(r.get('force_error'))} "
                     f"| {num(r.get('primary_penetration'))} | {num(r.get('secondary_penetration'))} "
                     f"| {', '.join(r.get('failed_checks', [])) or r.get('message', '')} |")
    return "\n".join(lines) + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", type=Path, default=VALIDATION.parent / "target" / "release" / "internodes")
    parser.add_argument("--dims", type=int, nargs="+", default=[2, 3])
    parser.add_argument("--only", default="", help="run only meshes whose name contains this")
    parser.add_argument("--no-report", action="store_true", help="print the rows, write no report")
    args = parser.parse_args()
    rows = []
    for dim in args.dims:
        for m, approach in cases(dim):
            if args.only not in m.name:
                continue
            for row in run(args.binary, m, approach, ("auto", CURVED[dim], "block")):
                rows.append(row)
                print(json.dumps({k: (round(v, 5) if isinstance(v, float) else v) for k, v in row.items()}),
                      flush=True)
    (BUILD / "rows.json").write_text(json.dumps(rows, indent=1))
    if not args.no_report:
        commit = subprocess.run(["git", "describe", "--always", "--dirty", "--abbrev=7"], cwd=VALIDATION,
                                capture_output=True, text=True).stdout.strip()
        if commit.endswith("-dirty"):
            print("foreign_meshes: the tree has uncommitted changes; no report written", file=sys.stderr)
            return 1
        REPORT.write_text(report(rows, commit))
    bad = [r for r in rows if r["verdict"] in ("WRONG", "FAILED TO RUN")]
    print(f"{len(rows)} runs, {len(bad)} wrong or failed")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
