#!/usr/bin/python3
"""Hertz suite: internodes on the geo/ contact cases of ``CASES`` at several mesh levels, against Hertz.

One row of ``CASES`` per geo script (the row's name is the script's): its bodies and surfaces, the
approach, Hertz's effective radius, the mesh sizes and the targets it is judged on. E = 1000,
nu = 0.3 on both bodies; the primary's support is pushed down by delta and held laterally, the
secondary's is clamped. The report lists each row's geometry (``geometry_lines``).

The curved body (the coarser upper one in the two-body cases) is the primary. Every case runs at
three levels, the contact-zone spacing halving (3D: h_c = R/33, R/67, R/133 with the far field
fixed; 2D: R/40, R/80, R/160 with every size halving); ``--quick`` runs the coarsest only, with
the same thresholds. Each level is solved frictionless with load steps 0.25, 0.5, 0.75, 1 (the
force-approach curve) and tied in one step. A row is judged at its finest level on the targets it
names (``TARGETS``); two equal bodies also on their symmetry plane.

Definitions (for each run, on its final step):

* P: the vertical contact force on the primary (``summary.json`` contact.force_primary);
* Hertz for that P, 1/R = 1/R1 + 1/R2 (R2 < 0 for a concave surface), 1/E* = 2 (1 - nu^2) / E:
  3D a_H = (3PR/(4E*))^(1/3), p0_H = 3P/(2 pi a_H^2); 2D a_H = sqrt(4PR/(pi E*)), p0_H = 2P/(pi a_H);
* a, p0: the solver's Hertz fit (least squares of p_i^2 against r_i^2 over the loaded active
  primary nodes, ``summary.json`` contact.hertz_fit);
* interface spacing h: mean length of the primary candidate-surface mesh edges within 0.15 of
  the contact axis (read from the .msh); the symmetry figure uses the finer (lower) surface;
* profile RMS: sqrt(mean_i (p_i - p_H(r_i))^2) / p0_H over every active primary node, p_i the
  nodal pressure -lambda . n (``/fields/contact_pressure``), r_i its distance from the contact
  axis in the reference configuration, p_H the Hertz ellipse of the measured P; the same RMS of
  the mean pressure (``/fields/contact_mean_pressure``) is listed beside it, for information;
* symmetry (two equal bodies): the largest distance of an active node of either body, deformed
  (x + u), from the symmetry plane v = -delta/2 (the upper support moves -delta, the lower one
  is clamped, so by symmetry the contact surface is that plane), over the finer spacing;
* observed convergence rate: least-squares slope of log(error) against log(h) over the levels.

Usage:  /usr/bin/python3 validation/hertz_suite.py [--quick] [--binary PATH] [--out DIR] [--reuse]

Meshes, case files, solver outputs and logs go to validation/build/hertz_suite/; the PNGs and
hertz_suite.json (checks and data) to --out (default validation/report/hertz_suite). ``--reuse``
keeps the output of a run whose case file, mesh and binary are unchanged (for re-plotting).
A full run takes about 10 minutes on 2 shared cores, most of it the two R/133 hemisphere solves.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import h5py
import numpy as np

VALIDATION = Path(__file__).resolve().parent
REPO = VALIDATION.parent

import hertz_theory  # noqa: E402
from compare import Check  # noqa: E402
from suite import (Figure, MeshFailed, SuiteResult, body_table, case_toml, contact_table, json_safe,  # noqa: E402
                   mesh_geo, run_solve, surface_spacing)

BUILD = VALIDATION / "build" / "hertz_suite"
YOUNGS_MODULUS = 1000.0
POISSON_RATIO = 0.3
E_STAR = hertz_theory.contact_modulus([(YOUNGS_MODULUS, POISSON_RATIO)] * 2)  # two identical bodies
LEVELS = (0, 1, 2)
LOAD_STEPS = (0.25, 0.5, 0.75, 1.0)
FORMULATIONS = ("frictionless", "tied")
SPACING_RADIUS = 0.15  # edges within this distance of the contact axis define h
REUSE = False  # --reuse: take a run's output from an earlier run of the same case, mesh and binary

# Targets at the finest level (frictionless), figure <= tolerance.
A_OVER_H_3D = 1.0  # |a - a_H| / h
RELATIVE_2D_A = 0.03  # |a / a_H - 1|
RELATIVE_P0 = 0.03  # |p0 / p0_H - 1|
PROFILE_RMS = 0.03  # RMS (p_i - p_H(r_i)) / p0_H
SYMMETRY = 0.01  # max distance from the symmetry plane / h
SHRINKS = 1.0  # finest error / coarsest error
QUANTITIES = {"a": "|a/a_H - 1|", "p0": "|p0/p0_H - 1|", "rms": "profile RMS / p0_H"}
# The targets a row can name: check -> (figure of ``analyse``, tolerance, note: a template filled
# with the run's numbers of ``analyse`` and ``numbers``, the fit against Hertz).
TARGETS = {
    "Hertz a / h": ("error_a_over_h", A_OVER_H_3D, "|a - a_H| / h; {numbers}"),
    "Hertz a": ("error_a", RELATIVE_2D_A, "|a/a_H - 1|; {numbers}"),
    "Hertz p0": ("error_p0", RELATIVE_P0, "|p0/p0_H - 1|; {numbers}"),
    "pressure RMS": ("error_rms", PROFILE_RMS, "RMS of nodal p - Hertz over {active_primary} active nodes / p0_H "
                                               "(mean pressure, for information: {rms_mean_pressure:.3f})"),
}


@dataclass
class HertzCase:
    """One geo/ contact case: its mesh script, bodies, supports, load and mesh levels."""

    name: str
    dim: int
    primary: str
    primary_surface: str
    primary_support: str
    secondary: str
    secondary_surface: str
    secondary_support: str
    delta: float  # imposed displacement of the primary's support, downwards
    radius: float  # effective radius 1/R = 1/R1 + 1/R2
    geo_parameters: dict  # level-independent gmsh parameters
    contact_spacing: float  # h_c at level 0 (the finer body's contact-zone size)
    refine_far_field: bool  # True: `level` scales every size; False: only h_c halves
    support_depths: tuple  # distances of the two supports from the contact point (Boussinesq)
    two_equal_bodies: bool
    sizes: dict = field(default_factory=dict)  # body dimensions seen from the contact, for the text
    targets: tuple = ()  # keys of TARGETS judged at the finest level

    def gmsh_parameters(self, level: int) -> dict:
        """-setnumber values of a level: h_c halves each level (and the far field if refined)."""
        if self.refine_far_field:
            return {**self.geo_parameters, "h_c": self.contact_spacing, "level": level}
        return {**self.geo_parameters, "h_c": self.contact_spacing / 2**level}


CASES = (
    HertzCase("hemisphere_on_block", 3, "sphere", "sphere_contact", "sphere_top", "block", "block_contact",
              "block_base", 0.01, 1.0, {"r_c": 0.16, "h_far": 0.5, "d_far": 1.0}, 0.03, False, (1.0, 2.0),
              False, {"block half-width W": 2.0, "block height H": 2.0, "hemisphere radius R": 1.0},
              ("Hertz a / h", "Hertz p0", "pressure RMS")),
    HertzCase("two_hemispheres", 3, "upper", "upper_contact", "upper_support", "lower", "lower_contact",
              "lower_support", 0.02, 0.5, {"r_c": 0.16, "h_far": 0.5, "d_far": 1.0, "ratio": 1.5}, 0.03, False,
              (1.0, 1.0), True, {"hemisphere radius R (each)": 1.0}),
    HertzCase("half_disc_on_block", 2, "disc", "disc_contact", "disc_top", "block", "block_contact", "block_base",
              0.02, 1.0, {"r_c": 0.2, "h_far": 0.5, "d_far": 2.0}, 0.025, True, (1.0, 2.0), False,
              {"block half-width W": 2.0, "block height H": 2.0, "half-disc radius R": 1.0}, ("Hertz a", "Hertz p0")),
    HertzCase("two_half_discs", 2, "upper", "upper_contact", "upper_support", "lower", "lower_contact",
              "lower_support", 0.03, 0.5, {"r_c": 0.2, "h_far": 0.5, "d_far": 2.0, "ratio": 1.5}, 0.025, True,
              (1.0, 1.0), True, {"half-disc radius R (each)": 1.0}),
    HertzCase("half_disc_in_groove", 2, "disc", "disc_contact", "disc_top", "block", "block_contact", "block_base",
              0.02, 1.5, {"r_c": 0.2, "h_far": 0.5, "d_far": 2.0}, 0.025, True, (1.0, 2.0), False,
              {"block half-width W": 2.0, "block depth H": 2.0, "half-disc radius R": 1.0, "groove radius R_g": 3.0},
              ("Hertz a", "Hertz p0")),
)


class RunFailed(RuntimeError):
    """Meshing or solving failed without usable output; the message says which and why."""


def boussinesq_correction(force: np.ndarray, depths: tuple) -> np.ndarray:
    """Half-space displacement on the axis at the support depths, summed over both bodies.

    A point at depth d under a load P moves w(d) = P (1 + nu)(3 - 2 nu) / (2 pi E d) less than
    the points at infinity Hertz's approach refers to, so the supports approach by
    delta_H(P) - w(d1) - w(d2): an estimate of the geometry effect (finite bodies, supports at
    a finite distance), for information only.
    """
    w = force * (1 + POISSON_RATIO) * (3 - 2 * POISSON_RATIO) / (2 * math.pi * YOUNGS_MODULUS)
    return sum(w / d for d in depths)


# ---------------------------------------------------------------------------
# Meshing and solving
# ---------------------------------------------------------------------------


def mesh(case: HertzCase, level: int) -> Path:
    """gmsh the case's geo script at a level into build/hertz_suite/meshes (cached)."""
    try:
        return mesh_geo(case.name, case.dim, case.gmsh_parameters(level),
                        BUILD / "meshes" / f"{case.name}_l{level}.msh")
    except MeshFailed as error:
        raise RunFailed(str(error)) from error


def case_file(case: HertzCase, msh: Path, formulation: str) -> str:
    """The TOML case of one run: primary support pushed down by delta, secondary support clamped."""
    components = ["ux", "uy", "uz"][: case.dim]
    zero = dict.fromkeys(components, 0.0)
    push = zero | {components[-1]: -case.delta}
    steps = {"load_steps": list(LOAD_STEPS)} if formulation == "frictionless" else {}
    contact = contact_table((case.primary, case.secondary), (case.primary_surface, case.secondary_surface),
                            case.primary, formulation, **steps)
    bodies = [body_table(case.primary, YOUNGS_MODULUS, POISSON_RATIO, [(case.primary_support, push)]),
              body_table(case.secondary, YOUNGS_MODULUS, POISSON_RATIO, [(case.secondary_support, zero)])]
    return case_toml(msh, "internodes", contact, bodies)


def solve(binary: Path, case: HertzCase, level: int, formulation: str) -> tuple[Path, Path, float]:
    """Mesh and solve one run; returns (msh, output folder, solve seconds).

    The CLI exits with status 1 on an unconverged contact status but still writes the last
    iterate: that is a result (its status check fails), not a crash.
    """
    msh = mesh(case, level)
    folder = BUILD / f"{case.name}_l{level}_{formulation}"
    folder.mkdir(parents=True, exist_ok=True)
    toml = folder / "case.toml"
    text = case_file(case, msh, formulation)
    output = folder / "internodes"
    stamp = {"case": text, "binary": str(binary), "binary_mtime": binary.stat().st_mtime,
             "mesh_mtime": msh.stat().st_mtime}
    done = folder / "done.json"
    if REUSE and done.is_file() and (output / "summary.json").is_file():
        previous = json.loads(done.read_text())
        if previous["stamp"] == stamp:
            return msh, output, previous["seconds"]
    done.unlink(missing_ok=True)
    toml.write_text(text)
    run = run_solve(binary, toml, output, log=folder / "log.txt")
    seconds = run.seconds
    if not (output / "summary.json").is_file() or not (output / "solution.h5").is_file():
        raise RunFailed(f"internodes solve {toml} (exit {run.exit}) wrote no solution: {run.tail(4)}")
    done.write_text(json.dumps({"stamp": stamp, "seconds": seconds}))
    return msh, output, seconds


# ---------------------------------------------------------------------------
# Post-processing of one run
# ---------------------------------------------------------------------------


def analyse(case: HertzCase, msh: Path, output: Path, formulation: str) -> dict:
    """Every number of one run (see the module doc), plus the per-node profile for the plots."""
    summary = json.loads((output / "summary.json").read_text())
    contact = summary["contact"]
    v = case.dim - 1
    names = [b["name"] for b in summary["bodies"]]
    with h5py.File(output / "solution.h5", "r") as h5:
        x = h5["mesh/geometry"][()]
        body = h5["mesh/node_body"][()]
        u = h5["fields/displacement"][()]
        p = h5["fields/contact_pressure"][()]
        p_mean = h5["fields/contact_mean_pressure"][()]
        active = h5["fields/contact_active"][()] == 1
        gap = h5["fields/normal_gap"][()]
    force = abs(contact["force_primary"][v])
    theory = hertz_theory.contact(force, case.radius, E_STAR, case.dim)
    fit = contact.get("hertz_fit") or {"a": math.nan, "p0": math.nan}
    h_primary = surface_spacing(msh, case.primary_surface, case.dim, SPACING_RADIUS)
    h_secondary = surface_spacing(msh, case.secondary_surface, case.dim, SPACING_RADIUS)

    on_primary = active & (body == names.index(case.primary))
    r = np.linalg.norm(x[on_primary][:, :v], axis=1)
    p_hertz = theory["p0"] * np.sqrt(np.maximum(0.0, 1 - (r / theory["a"]) ** 2))
    rms = float(np.sqrt(np.mean((p[on_primary] - p_hertz) ** 2)) / theory["p0"]) if on_primary.any() else math.nan
    inner = r <= 0.8 * theory["a"]
    rms_inner = float(np.sqrt(np.mean((p[on_primary][inner] - p_hertz[inner]) ** 2)) / theory["p0"])
    # The same RMS for the mean pressure (nodal force / nodal area, the solver's tension test and
    # Hertz fit, and the dolfinx reference's recovery), for information beside the target's.
    rms_mean = (float(np.sqrt(np.mean((p_mean[on_primary] - p_hertz) ** 2)) / theory["p0"])
                if on_primary.any() else math.nan)

    result = {
        "formulation": formulation,
        "status": contact["status"],
        "iterations": sum(s["iterations"] for s in contact.get("steps", [])) or len(contact.get("iterations", [])),
        "iterations_per_step": [s["iterations"] for s in contact.get("steps", [])],
        "force": force,
        "force_secondary": abs(contact["force_secondary"][v]),
        "force_imbalance": contact["force_imbalance"],
        "active_primary": int(on_primary.sum()),
        "a": fit["a"],
        "p0": fit["p0"],
        "a_hertz": theory["a"],
        "p0_hertz": theory["p0"],
        "h": h_primary,
        "h_secondary": h_secondary,
        "error_a": abs(fit["a"] / theory["a"] - 1),
        "error_a_over_h": abs(fit["a"] - theory["a"]) / h_primary,
        "error_p0": abs(fit["p0"] / theory["p0"] - 1),
        "error_rms": rms,
        "rms_inside_0.8a": rms_inner,
        "rms_mean_pressure": rms_mean,
        "a_nodes": float(r[p[on_primary] > 0].max()) if (p[on_primary] > 0).any() else math.nan,
        "steps": [{"load_factor": s["load_factor"], "delta": s["load_factor"] * case.delta,
                   "status": s["status"], "force": abs(s["force_primary"][v])} for s in contact.get("steps", [])],
        "profile": {"r": r.tolist(), "x": x[on_primary][:, 0].tolist(), "p": p[on_primary].tolist()},
    }
    # Inactive candidates penetrating beyond the solver's tolerance (1e-3 h): none if converged.
    penetrating = ~active & (gap < -1e-3 * min(h_primary, h_secondary))
    result["penetrating"] = {
        "count": int(penetrating.sum()),
        "deepest_over_h": float(-gap[penetrating].min() / min(h_primary, h_secondary)) if penetrating.any() else 0.0,
        "r_range": [float(np.linalg.norm(x[penetrating][:, :v], axis=1).min()),
                    float(np.linalg.norm(x[penetrating][:, :v], axis=1).max())] if penetrating.any() else [],
        "primary_active_radius": float(r.max()) if on_primary.any() else math.nan,
    }
    if case.two_equal_bodies:
        result |= symmetry(case, x, u, active, body == names.index(case.primary), min(h_primary, h_secondary))
    return result


def symmetry(case: HertzCase, x: np.ndarray, u: np.ndarray, active: np.ndarray, primary: np.ndarray,
             h: float) -> dict:
    """Distances of the active nodes (both bodies, deformed) from the symmetry plane v = -delta/2.

    ``symmetry_over_h`` (the checked figure) takes every active node of both surfaces. For
    information: the same over the nodes inside the primary's contact zone (r at most the largest r
    of an active primary node; secondary active nodes beyond it are the ring Algorithm 2 keeps
    around the zone, where Hertz's own gap opens), and the mean offset (a rigid shift of the
    contact surface: the two meshes' different compliance).
    """
    v = case.dim - 1
    offset = x[:, v] + u[:, v] + case.delta / 2
    r = np.linalg.norm(x[:, :v], axis=1)
    if not (active & primary).any():
        return {"symmetry_distance": math.nan, "symmetry_over_h": math.nan, "h_fine": h}
    zone = active & (r <= r[active & primary].max())
    worst = np.flatnonzero(active)[np.argmax(np.abs(offset[active]))]
    return {
        "symmetry_distance": float(np.abs(offset[active]).max()),
        "symmetry_over_h": float(np.abs(offset[active]).max() / h),
        "symmetry_worst_node": {"primary": bool(primary[worst]), "r": float(r[worst]),
                                "zone_radius": float(r[active & primary].max())},
        "symmetry_in_zone_over_h": float(np.abs(offset[zone]).max() / h),
        "symmetry_mean_offset_over_h": float(offset[active].mean() / h),
        "h_fine": h,
    }


def observed_rate(h: list, error: list) -> float:
    """Least-squares slope of log(error) against log(h) (NaN with fewer than two usable levels)."""
    points = [(math.log(a), math.log(b)) for a, b in zip(h, error) if b > 0 and math.isfinite(b)]
    if len(points) < 2:
        return math.nan
    return float(np.polyfit(*zip(*points), 1)[0])


# ---------------------------------------------------------------------------
# Checks
# ---------------------------------------------------------------------------


def target_checks(case: HertzCase, finest: dict, level: int) -> list[Check]:
    """The accuracy targets at the finest level run (frictionless)."""
    where = f"{case.name} l{level} frictionless"
    numbers = (f"a = {finest['a']:.5f}, a_H = {finest['a_hertz']:.5f}, p0 = {finest['p0']:.4g}, "
               f"p0_H = {finest['p0_hertz']:.4g}, h = {finest['h']:.4g}")
    checks = []
    for target in case.targets:
        key, tolerance, note = TARGETS[target]
        checks.append(Check(target, where, finest[key], tolerance, note.format(numbers=numbers, **finest)))
    if case.two_equal_bodies:
        worst = finest.get("symmetry_worst_node", {})
        checks.append(Check("symmetry plane", where, finest["symmetry_over_h"], SYMMETRY,
                            f"max distance {finest['symmetry_distance']:.3e} of active nodes (both bodies, "
                            f"deformed) from v = -delta/2, over h = {finest['h_fine']:.4g}; worst node on the "
                            f"{'primary' if worst.get('primary') else 'secondary'} at r = "
                            f"{worst.get('r', math.nan):.4f} "
                            f"(primary zone r <= {worst.get('zone_radius', math.nan):.4f}); inside that zone "
                            f"{finest.get('symmetry_in_zone_over_h', math.nan):.3g} h, mean offset "
                            f"{finest.get('symmetry_mean_offset_over_h', math.nan):+.3g} h; status {finest['status']}"))
    for c in checks:
        if not c.passed:
            c.note += f" -- MISSED: {c.figure:.3g} > {c.tolerance:g}"
    return checks


def status_check(case: HertzCase, formulation: str, runs: dict) -> Check:
    """Number of levels whose solve did not end converged (must be 0)."""
    states = [f"l{level}: {r['status']} ({'+'.join(map(str, r['iterations_per_step'])) or r['iterations']} its)"
              if "status" in r else f"l{level}: {r['error']}"
              for level, r in runs.items()]
    bad = sum(r.get("status") != "converged" for r in runs.values())
    return Check("solve converged", f"{case.name} {formulation}", bad, 0, "; ".join(states))


def shrink_checks(case: HertzCase, formulation: str, runs: dict) -> list[Check]:
    """finest error / coarsest error <= 1 for a, p0 and the profile RMS (needs two levels)."""
    levels = sorted(level for level, r in runs.items() if "status" in r)
    if len(levels) < 2:
        return []
    coarse, fine = runs[levels[0]], runs[levels[-1]]
    checks = []
    for key, label in QUANTITIES.items():
        e0, e1 = coarse[f"error_{key}"], fine[f"error_{key}"]
        rate = observed_rate([runs[lv]["h"] for lv in levels], [runs[lv][f"error_{key}"] for lv in levels])
        c = Check(f"{key} error shrinks", f"{case.name} {formulation}", e1 / e0 if e0 > 0 else math.nan, SHRINKS,
                  f"{label}: l{levels[0]} {e0:.3g} -> l{levels[-1]} {e1:.3g}, observed rate {rate:.2f}")
        if not c.passed:
            c.note += " -- does NOT shrink"
        checks.append(c)
    return checks


# ---------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_profiles(case: HertzCase, runs: dict, path: Path) -> bool:
    """p / p0_H against r / a_H (x / a_H in 2D) at every level, with the unit Hertz ellipse; False if no run."""
    plt = _pyplot()
    levels = sorted(lv for lv in runs["frictionless"] if "status" in runs["frictionless"][lv])
    if not levels:
        return False
    fig, axes = plt.subplots(1, len(levels), figsize=(4.2 * len(levels), 3.8), squeeze=False, sharey=True)
    s = np.linspace(-1.0 if case.dim == 2 else 0.0, 1.0, 201)
    for ax, level in zip(axes[0], levels):
        ax.plot(s, np.sqrt(1 - s**2), "k-", lw=1, label="Hertz")
        for formulation, marker in (("frictionless", "o"), ("tied", "x")):
            run = runs[formulation].get(level, {})
            if "profile" not in run:
                continue
            coordinate = run["profile"]["x" if case.dim == 2 else "r"]
            ax.plot(np.array(coordinate) / run["a_hertz"], np.array(run["profile"]["p"]) / run["p0_hertz"], marker,
                    ms=3, mfc="none", alpha=0.7, label=f"{formulation}, RMS {run['error_rms']:.3f}")
        run = runs["frictionless"][level]
        ax.set_title(f"level {level}: h = {run['h']:.4f} (a_H/h = {run['a_hertz'] / run['h']:.1f})", fontsize=9)
        ax.set_xlabel("x / a_H" if case.dim == 2 else "r / a_H")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    axes[0][0].set_ylabel("nodal pressure -lambda.n / p0_H")
    fig.suptitle(f"{case.name}: active primary nodes\nagainst the Hertz ellipse of the measured force", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def plot_force_approach(cases: list, results: dict, path: Path) -> None:
    """P(delta) per case and level (frictionless load steps); 3D: Hertz's law and its estimate."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(cases), figsize=(4.2 * len(cases), 3.8), squeeze=False)
    for ax, case in zip(axes[0], cases):
        runs = results[case.name]["frictionless"]
        for level in sorted(runs):
            steps = runs[level].get("steps", [])
            if steps:
                line, = ax.plot([0] + [s["delta"] for s in steps], [0] + [s["force"] for s in steps], "o-", ms=3,
                                label=f"level {level}, h = {runs[level]['h']:.4f}")
                bad = [s for s in steps if s["status"] != "converged"]
                if bad:
                    ax.plot([s["delta"] for s in bad], [s["force"] for s in bad], "x", ms=9, mew=2,
                            color=line.get_color(), label=f"level {level}: {bad[0]['status']} (last iterate)")
        if case.dim == 3:
            largest = max((s["force"] for r in runs.values() for s in r.get("steps", [])), default=1.0)
            force = np.linspace(0, largest, 101)
            delta = hertz_theory.approach_3d(force, case.radius, E_STAR)
            ax.plot(delta, force, "k--", lw=1, label="Hertz half-space 4/3 E* R^1/2 d^3/2")
            ax.plot(delta - boussinesq_correction(force, case.support_depths), force, "k:", lw=1,
                    label="Hertz, supports at finite depth (estimate)")
            ax.set_xlim(0, case.delta * 1.05)
        ax.set_title(case.name, fontsize=9)
        ax.set_xlabel("imposed approach of the supports")
        ax.set_ylabel("contact force P" + (" per unit length" if case.dim == 2 else ""))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_convergence(case: HertzCase, runs: dict, rates: dict, path: Path) -> None:
    """Errors of a, p0 and the profile RMS against h, both formulations, log-log."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(QUANTITIES), figsize=(4.2 * len(QUANTITIES), 3.8), squeeze=False)
    for ax, (key, label) in zip(axes[0], QUANTITIES.items()):
        for formulation, marker in (("frictionless", "o-"), ("tied", "s--")):
            levels = sorted(lv for lv, r in runs[formulation].items() if "status" in r)
            h = [runs[formulation][lv]["h"] for lv in levels]
            e = [runs[formulation][lv][f"error_{key}"] for lv in levels]
            ax.loglog(h, e, marker, ms=4, label=f"{formulation}, rate {rates[formulation][key]:.2f}")
        ax.set_xlabel("interface spacing h")
        ax.set_title(label, fontsize=9)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    fig.suptitle(f"{case.name}: error against Hertz (for the measured force) under refinement", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ---------------------------------------------------------------------------
# Text
# ---------------------------------------------------------------------------


def level_table(case: HertzCase, runs: dict) -> str:
    """Per level and formulation: sizes, force, a, p0 and their errors, RMS, status, time."""
    rows = ["| formulation | level | h | a_H / h | P | a / a_H | p0 / p0_H | \\|a - a_H\\| / h | RMS | RMS r<0.8a "
            "| RMS mean p | imbalance | status (its) | seconds |"
            + (" symmetry / h_fine | in zone / h_fine | mean offset / h_fine |" if case.two_equal_bodies else ""),
            "|---" * (14 + 3 * case.two_equal_bodies) + "|"]
    for formulation in FORMULATIONS:
        for level, r in sorted(runs[formulation].items()):
            if "status" not in r:
                rows.append(f"| {formulation} | {level} | " + r["error"].replace("|", "/") + " |")
                continue
            rows.append(
                f"| {formulation} | {level} | {r['h']:.4f} | {r['a_hertz'] / r['h']:.1f} | {r['force']:.4g} "
                f"| {r['a'] / r['a_hertz']:.4f} | {r['p0'] / r['p0_hertz']:.4f} | {r['error_a_over_h']:.3f} "
                f"| {r['error_rms']:.3f} | {r['rms_inside_0.8a']:.3f} | {r['rms_mean_pressure']:.3f} "
                f"| {r['force_imbalance']:.1e} "
                f"| {r['status']} ({r['iterations']}) | {r['seconds']:.1f} |"
                + (f" {r['symmetry_over_h']:.3g} | {r['symmetry_in_zone_over_h']:.3g} "
                   f"| {r['symmetry_mean_offset_over_h']:+.3g} |" if case.two_equal_bodies else ""))
    return "\n".join(rows)


def unconverged_lines(results: dict) -> str:
    """One line per run that did not converge: where its last iterate still penetrates."""
    lines = []
    for name, runs in results.items():
        for formulation, by_level in runs.items():
            for level, r in sorted(by_level.items()):
                if "status" not in r:
                    lines.append(f"* `{name}` level {level} {formulation}: no solution ({r['error']})")
                elif r["status"] != "converged":
                    pen = r["penetrating"]
                    where = (f", at r = {pen['r_range'][0]:.4f}-{pen['r_range'][1]:.4f} against active primary "
                             f"nodes up to r = {pen['primary_active_radius']:.4f}" if pen["count"] else "")
                    lines.append(f"* `{name}` level {level} {formulation}: {r['status']}; its last iterate has "
                                 f"{pen['count']} inactive candidate nodes (both surfaces) penetrating by up to "
                                 f"{pen['deepest_over_h']:.3g} h_fine{where}.")
    if not lines:
        return "Every run converged."
    return "**Runs that did not converge** (their numbers above are last iterates):\n\n" + "\n".join(lines)


def rate_table(rates: dict) -> str:
    """Observed rates per case and formulation."""
    rows = ["| case | formulation | rate a | rate p0 | rate RMS |", "|---|---|---|---|---|"]
    for name, by_formulation in rates.items():
        for formulation, r in by_formulation.items():
            rows.append(f"| {name} | {formulation} | {r['a']:.2f} | {r['p0']:.2f} | {r['rms']:.2f} |")
    return "\n".join(rows)


def check_table(checks: list[Check]) -> str:
    """Every check with its tolerance and PASS / FAIL."""
    rows = ["| check | case | figure | tolerance | result |", "|---|---|---|---|---|"]
    rows += [f"| {c.check} | {c.case} | {c.figure:.3g} | {c.tolerance:g} | {'PASS' if c.passed else 'FAIL'} |"
             for c in checks]
    return "\n".join(rows)


GEOMETRY_TEXT = """\
**Geometry and meshes.** E = 1000, nu = 0.3 on both bodies (E* = E / (2 (1 - nu^2)) = {e_star:.2f}).
The contact zone r < r_c is meshed at h_c (per case below), halving per level; in 3D only h_c
halves (the far field stays at h_far, to keep the largest mesh small), in 2D every size halves
(gmsh `level`). Per case:

{geometry}

The bodies are not half-spaces: Hertz's a(P) and p0(P) carry a modelling error of order (a/R)^2 and
a / (body size), which no refinement removes; the errors below tend to that floor, not to zero.
"""

def force_table(cases: list, results: dict) -> str:
    """Force against approach at the finest level; 3D: against Hertz's law and its estimate."""
    rows = ["| case | level | delta | P | status | P / P_Hertz(delta) | (delta_H(P) - w(P)) / delta |",
            "|---|---|---|---|---|---|---|"]
    for case in cases:
        runs = {lv: r for lv, r in results[case.name]["frictionless"].items() if r.get("steps")}
        if not runs:
            continue
        level = max(runs)
        for step in runs[level]["steps"]:
            if case.dim == 3:
                delta_h = hertz_theory.approach_3d(step["force"], case.radius, E_STAR)
                estimate = delta_h - boussinesq_correction(step["force"], case.support_depths)
                ratios = f"{(delta_h / step['delta']) ** 1.5:.3f} | {estimate / step['delta']:.3f}"
            else:
                ratios = "- | -"
            rows.append(f"| {case.name} | {level} | {step['delta']:g} | {step['force']:.4g} | {step['status']} "
                        f"| {ratios} |")
    return "\n".join(rows)


FORCE_TEXT = """\
**Force against approach** (frictionless load steps, finest level). delta is the imposed approach
of the two supports. In 3D, P / P_Hertz(delta) compares with Hertz's half-space law
P = 4/3 E* R^1/2 delta^3/2 (information only, not a check): the supports sit at a finite depth
(R = 1 in the curved bodies, H = 2 in the block) and move less than the points at infinity Hertz's
approach refers to, by w(P) = P (1 + nu)(3 - 2 nu) / (2 pi E d) per support (Boussinesq, half-space
estimate). (delta_H(P) - w(P)) / delta close to 1 says that geometry effect explains the difference.
In 2D the approach depends logarithmically on the body size and supports: no closed form is shown.
"""


def limits_text(results: dict, rates: dict) -> str:
    """What limits the accuracy, with the measured figures of this run."""
    def finest(name: str) -> dict:
        runs = results[name]["frictionless"]
        done = [lv for lv, r in runs.items() if "status" in r]
        return runs[max(done)] if done else {}

    hob, hdob = finest("hemisphere_on_block"), finest("half_disc_on_block")
    rms_3d = (f"{hob['error_rms']:.3f} of p0 at h = {hob['h']:.4f} (inside 0.8 a: {hob['rms_inside_0.8a']:.3f}), "
              f"observed rate {rates['hemisphere_on_block']['frictionless']['rms']:.2f}; the mean pressure "
              f"(nodal force / nodal area) scatters by {hob['rms_mean_pressure']:.3f}" if hob else "not measured")
    rms_2d = f"{hdob['error_rms']:.3f} at h = {hdob['h']:.4f}" if hdob else "not measured"
    return LIMITS_TEXT.format(rms_3d=rms_3d, rms_2d=rms_2d)


LIMITS_TEXT = """\
**What limits the accuracy.**
* Discretisation of the rim: the contact zone ends between two nodes, so the fitted a moves by
  fractions of h; p0 comes from the same least-squares fit of p^2 against r^2 over the active nodes
  (the solver's fit of the mean pressure, nodal force / nodal area), which the rim nodes pull on.
* Nodal pressure scatter (3D): the nodal pressure -lambda.n of neighbouring nodes differs by tens of
  percent of p0 (the P1 multiplier on an unstructured triangulation, and the RBF interpolation error
  of the gaps, about 0.05 h for a linear field, answered by a pressure of about E* x gap / h). Measured
  here: profile RMS {rms_3d}. It falls under refinement but stays well above the 3% target
  at the finest level. In 2D (interpolation along a curve) it is {rms_2d}, most of it from
  the rim nodes.
* Modelling: Hertz assumes half-spaces and a << R; with a / R = 0.1 and bodies 10-20 a in size the
  a and p0 errors level off at the per-mille to percent level (see the floor in the convergence plots).
  Where the coarsest level is already at that floor, the error moves within it, up or down, under
  refinement, and an "error shrinks" target can miss although every level meets the 3% target.
* Mesh: in 3D only the contact zone is refined (the far field stays at h_far = 0.5), so the
  stiffness of the far field, and with it P(delta) and the compliance difference between the two
  bodies' meshes (a rigid shift of the contact surface of two equal bodies), carries an error that
  does not fall with the levels. a(P) and p0(P) are local and do not depend on it.
* Solver: a run that ends cycling or at the iteration cap reports its last iterate, whose contact
  zone can be truncated; its numbers are in the tables but are not a converged result.
"""


def geometry_lines(cases: list, results: dict) -> str:
    """One line per case: body sizes against a at the finest level run."""
    lines = []
    for case in cases:
        runs = results[case.name]["frictionless"]
        done = [r for _, r in sorted(runs.items()) if "status" in r]
        a = done[-1]["a_hertz"] if done else math.nan
        sizes = ", ".join(f"{name} {size:g} = {size / a:.1f} a" for name, size in case.sizes.items())
        lines.append(f"* `{case.name}`: delta = {case.delta}, R_eff = {case.radius}; r_c = "
                     f"{case.geo_parameters['r_c']:g}, h_c = {case.contact_spacing:g} at level 0; a_H = {a:.4f} at "
                     f"the finest level (a / R_eff = {a / case.radius:.3f}); {sizes}.")
    return "\n".join(lines)


# ---------------------------------------------------------------------------
# The suite
# ---------------------------------------------------------------------------


def run_case(binary: Path, case: HertzCase, levels: tuple) -> dict:
    """Every level and formulation of one case: {formulation: {level: numbers or {'error': ...}}}."""
    runs: dict = {formulation: {} for formulation in FORMULATIONS}
    for level in levels:
        for formulation in FORMULATIONS:
            print(f"  {case.name} level {level} {formulation} ...", end=" ", flush=True)
            try:
                msh, output, seconds = solve(binary, case, level, formulation)
                runs[formulation][level] = analyse(case, msh, output, formulation) | {"seconds": seconds}
                r = runs[formulation][level]
                print(f"{r['status']} ({r['iterations']} its, {seconds:.1f} s): P {r['force']:.4g}, "
                      f"a/a_H {r['a'] / r['a_hertz']:.4f}, p0/p0_H {r['p0'] / r['p0_hertz']:.4f}, "
                      f"RMS {r['error_rms']:.3f}", flush=True)
            except (RunFailed, OSError, KeyError, ValueError) as error:
                runs[formulation][level] = {"error": f"{type(error).__name__}: {error}"}
                print(f"failed: {error}", flush=True)
    return runs


def run_suite(binary: Path, quick: bool, out_dir: Path) -> SuiteResult:
    """Run the Hertz suite; PNGs into out_dir, scratch under validation/build/hertz_suite."""
    start = time.perf_counter()
    out_dir.mkdir(parents=True, exist_ok=True)
    levels = LEVELS[:1] if quick else LEVELS
    results, rates, checks, figures, tables = {}, {}, [], [], []
    for case in CASES:
        case_start = time.perf_counter()
        runs = run_case(binary, case, levels)
        results[case.name] = runs
        rates[case.name] = {}
        for formulation in FORMULATIONS:
            done = sorted(lv for lv, r in runs[formulation].items() if "status" in r)
            rates[case.name][formulation] = {
                key: observed_rate([runs[formulation][lv]["h"] for lv in done],
                                   [runs[formulation][lv][f"error_{key}"] for lv in done]) for key in QUANTITIES}
            checks.append(status_check(case, formulation, runs[formulation]))
        finest = max((lv for lv, r in runs["frictionless"].items() if "status" in r), default=None)
        if finest is None:
            checks.append(Check("Hertz targets", case.name, math.nan, 0, "no frictionless run gave a solution"))
        else:
            checks += target_checks(case, runs["frictionless"][finest], finest)
        for formulation in FORMULATIONS:
            checks += shrink_checks(case, formulation, runs[formulation])

        profile_png = out_dir / f"hertz_profile_{case.name}.png"
        if plot_profiles(case, runs, profile_png):
            figures.append(Figure(f"{case.name}: nodal pressure of the active primary nodes against the Hertz "
                                  f"ellipse of the measured force, per level (normalised by a_H, p0_H)", profile_png))
        if len(levels) > 1 and finest is not None:
            convergence_png = out_dir / f"hertz_convergence_{case.name}.png"
            plot_convergence(case, runs, rates[case.name], convergence_png)
            figures.append(Figure(f"{case.name}: errors of a, p0 and the profile RMS against h, log-log, "
                                  f"with least-squares rates", convergence_png))
        tables.append(f"### {case.name}\n\n{level_table(case, runs)}\n\n"
                      f"Wall time of the case (mesh + both formulations, all levels): "
                      f"{time.perf_counter() - case_start:.0f} s"
                      f"{' (solves reused from an earlier run of the same binary)' if REUSE else ''}.")

    force_png = out_dir / "hertz_force_approach.png"
    plot_force_approach(list(CASES), results, force_png)
    figures.append(Figure("Force against the imposed approach (frictionless load steps 0.25-1) per level; 3D: "
                          "Hertz's half-space law and its estimate with the supports at finite depth, for "
                          "information", force_png))

    seconds = time.perf_counter() - start
    text = "\n\n".join([
        f"Hertz suite ({'quick: coarsest level only' if quick else 'levels ' + ', '.join(map(str, levels))}), "
        f"total wall time {seconds:.0f} s"
        f"{'; the solves were reused from an earlier run of the same binary (run.py --reuse), whose solve times the tables list' if REUSE else ''}.",
        GEOMETRY_TEXT.format(e_star=E_STAR, geometry=geometry_lines(list(CASES), results)),
        "**Per level** (a, p0: the solver's Hertz fit; a_H, p0_H: Hertz for the measured force P; RMS: "
        "nodal pressure against the Hertz ellipse over the active primary nodes, in units of p0_H; RMS mean p: "
        "the same for the mean pressure, nodal force / nodal area; h: the "
        "primary's interface spacing, the coarser one in the two-body cases; h_fine: the finer surface's; "
        "seconds: the solve's wall time).",
        *tables,
        unconverged_lines(results),
        "**Observed convergence rates** (least squares of log error against log h)"
        + (":\n\n" + rate_table(rates) if len(levels) > 1 else ": not computed in quick mode (one level)."),
        FORCE_TEXT + "\n" + force_table(list(CASES), results),
        "**Checks**\n\n" + check_table(checks),
        limits_text(results, rates),
    ])
    data = {"levels": list(levels), "quick": quick, "seconds": seconds, "young_modulus": YOUNGS_MODULUS,
            "poisson_ratio": POISSON_RATIO, "E_star": E_STAR, "load_steps": list(LOAD_STEPS),
            "cases": {c.name: asdict(c) for c in CASES}, "rates": rates, "results": json_safe(results)}
    return SuiteResult(f"Hertz contact: {len(CASES)} cases under refinement", checks, figures, text, data)


def main() -> int:
    """Run the suite, print the text and the checks; 0 if every check passes."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="coarsest level only")
    parser.add_argument("--binary", type=Path, default=REPO / "target/release/internodes")
    parser.add_argument("--out", type=Path, default=VALIDATION / "report" / "hertz_suite")
    parser.add_argument("--reuse", action="store_true",
                        help="reuse outputs of earlier runs with the same case file, mesh and binary")
    args = parser.parse_args()
    global REUSE
    REUSE = args.reuse
    result = run_suite(args.binary, args.quick, args.out)
    print()
    print(result.text)
    print()
    for c in result.checks:
        print(f"{'PASS' if c.passed else 'FAIL'}  {c.check:<22} {c.case:<38} {c.figure:>10.3g} <= {c.tolerance:<6g} "
              f"{c.note}")
    (args.out / "hertz_suite.json").write_text(json.dumps(
        {"checks": [asdict(c) | {"figure": c.figure if math.isfinite(c.figure) else None, "passed": c.passed}
                    for c in result.checks], "data": result.data}, indent=1))
    print(f"\nfigures and hertz_suite.json in {args.out}")
    return 0 if all(c.passed for c in result.checks) else 1


if __name__ == "__main__":
    sys.exit(main())
