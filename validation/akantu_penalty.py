"""Akantu 5.0.7's penalty contact on the 2D (plane strain) Hertz case, for comparison with ours.

Run with the Akantu wheel's interpreter (``make akantu`` installs it; ``akantu_suite.py`` calls
this script):

    build/akantu/bin/python validation/akantu_penalty.py --mesh MESH.msh --out RESULT.json
        --epsilon EPS_N --delta DELTA --steps N [--youngs 1000] [--poisson 0.3]
        [--block-youngs E] [--rigid-master]

``--rigid-master`` sets ``is_master_deformable = false``: the block receives no contact force and
stays as meshed (a rigid flat), and Akantu applies the whole slave force (no ``alpha``: matched
to ours at ``eps = epsilon_n``, the forces agree to 4e-6 at ``epsilon_n = 1e7``, ``akantu_suite.py``).

``MESH.msh`` is ``geo/half_disc_on_block.geo`` meshed by gmsh (MSH 4.1 is read as is). The disc
("disc_contact", Akantu's slave) is pressed onto the block ("block_contact", the master,
deformable, frictionless) by ``uy = -DELTA`` on "disc_top" (``ux = 0`` there too; "block_base"
clamped), in N equal increments, each solved by Akantu's implicit static Newton solver
(``coupler.solveStep()``, residual norm relative to the increment's first one below ``RTOL``;
Akantu gives up after ``MAX_ITERATIONS + 1`` iterations).

What ``epsilon_n`` means (Akantu's ``penalty_linear`` resolution, source at tag v5.0.7): a
traction per unit penetration, i.e. a pressure per length, not a force per length.
``ResolutionPenalty::computeNormalForce`` (src/model/contact_mechanics/resolutions/
resolution_penalty.cc) gives a slave node the normal force ``epsilon_n * gap * nodal_area`` (and
the master nodes their shares by the shape functions), ``nodal_area`` being the node's share of
the contact surface, in 2D its tributary length (``ContactMechanicsModel::computeNodalAreas``,
src/model/contact_mechanics/contact_mechanics_model.cc). With ``is_master_deformable = true``,
``Resolution::assembleLocalToGlobalArray`` (src/model/contact_mechanics/resolution.cc) scales
this by ``alpha = 0.5`` and *assigns* (``=``, not ``+=``) the master nodes' shares, so the force
applied to a slave node is ``0.5 * epsilon_n * gap * length`` and the block receives less than
the disc (``block_base_force`` below shows it), while ``assembleLocalToGlobalMatrix`` adds the
full ``epsilon_n`` stiffness, every (i, j) entry, into the coupler's symmetric (upper-triangle)
matrix "K", which counts its off-diagonal entries twice. Newton's tangent is therefore not the
residual's derivative: Newton converges linearly at best. On this case (h_c = 0.0125, E = 1000)
the iteration counts grow with ``epsilon_n`` and the contact zone, Newton diverges from
``epsilon_n`` = 1e4 up, and at 1e2 the last increment fails when the pole, sunk ~1.5 spacings,
falls in a gap between two master segments' orthogonal projections and loses its contact element.

Written to ``--out`` (JSON): ``akantu`` (version), ``epsilon_n``, ``epsilon_meaning``, ``steps``
(one per increment run: ``step``, ``delta``, ``converged``, ``iterations``, ``force`` = the
vertical reaction on disc_top, the sum of the solid's internal forces there, positive when
pressing; ``block_base_force`` = the same on block_base, sign such that it equals ``force`` in
equilibrium; ``max_gap`` = Akantu's largest slave gap (penetration); ``n_contact`` = Akantu's
contact elements, each a penetrating slave node; ``max_penetration`` and ``n_penetrating`` = the
same measured geometrically, the slave nodes' depth below the deformed block top, which also
counts nodes Akantu's detection misses), ``converged`` (all N increments converged), ``force``
(the last increment's force if all converged, else null), ``error`` (message or null). The run
stops at the first increment that does not converge or raises. Exit 0 once the JSON is written,
1 if it cannot be.
"""

import argparse
import json
import sys
import tempfile
import time
import traceback
from pathlib import Path

import numpy as np

MAX_ITERATIONS = 50   # Newton iterations per increment
RTOL = 1e-8           # residual norm relative to the increment's first residual
TIME_BUDGET = 240.0   # seconds; no new increment starts after this

INPUT = """
material elastic [
  name = disc
  rho = 1
  E = {E!r}
  nu = {nu!r}
]
material elastic [
  name = block
  rho = 1
  E = {E_block!r}
  nu = {nu!r}
]
contact_detector [
  type = explicit
  master = block_contact
  slave = disc_contact
  projection_tolerance = 1e-10
  max_iterations = 100
  extension_tolerance = 1e-5
]
contact_resolution penalty_linear [
  name = disc_contact
  mu = 0
  epsilon_n = {eps!r}
  epsilon_t = 0
  is_master_deformable = {deformable}
]
"""

MEANING = ("traction per unit penetration (pressure per length): the force on a slave node is "
           "epsilon_n * gap * nodal_area (its tributary length in 2D), "
           "ResolutionPenalty::computeNormalForce in "
           "src/model/contact_mechanics/resolutions/resolution_penalty.cc; with "
           "is_master_deformable = true, Resolution::assembleLocalToGlobalArray "
           "(src/model/contact_mechanics/resolution.cc) applies half of it, "
           "0.5 * epsilon_n * gap * nodal_area, while the tangent keeps the full epsilon_n")


def finite(x):
    """A float for JSON, or None where Akantu's state went non-finite."""
    return float(x) if np.isfinite(x) else None


def run(args, result):
    import akantu as aka
    result["akantu"] = aka.__version__

    with tempfile.TemporaryDirectory() as tmp:
        dat = Path(tmp) / "input.dat"
        dat.write_text(INPUT.format(E=args.youngs, E_block=args.block_youngs or args.youngs, nu=args.poisson,
                                    eps=args.epsilon, deformable="false" if args.rigid_master else "true"))
        aka.parseInput(str(dat))  # plane strain is the elastic material's default

    mesh = aka.Mesh(2)
    mesh.read(args.mesh)
    coupler = aka.CouplerSolidContact(mesh)
    solid = coupler.getSolidMechanicsModel()
    contact = coupler.getContactMechanicsModel()
    solid.setMaterialSelector(aka.MeshDataMaterialSelectorString("physical_names", solid))
    coupler.initFull(_analysis_method=aka._static)
    contact.getContactDetector().setSurfaceSelector(aka.PhysicalSurfaceSelector(mesh))

    coupler.applyBC(aka.FixedValue(0.0, aka._x), "block_base")
    coupler.applyBC(aka.FixedValue(0.0, aka._y), "block_base")
    coupler.applyBC(aka.FixedValue(0.0, aka._x), "disc_top")

    solver = coupler.getNonLinearSolver()
    solver.set("max_iterations", MAX_ITERATIONS)
    solver.set("threshold", RTOL)
    solver.set("convergence_type", aka.SolveConvergenceCriteria.residual)

    def nodes(group):
        return mesh.getElementGroup(group).getNodeGroup().getNodes()[:, 0].copy()

    top, base, slave, master = (nodes(g) for g in
                                ("disc_top", "block_base", "disc_contact", "block_contact"))
    X = mesh.getNodes().copy()
    master = master[np.argsort(X[master, 0])]  # the block top, left to right

    start = time.monotonic()
    for k in range(1, args.steps + 1):
        if time.monotonic() - start > TIME_BUDGET:
            result["error"] = f"time budget of {TIME_BUDGET:.0f} s spent before increment {k}"
            return
        delta = args.delta * k / args.steps
        coupler.applyBC(aka.FixedValue(-delta, aka._y), "disc_top")
        error = None
        try:
            coupler.solveStep()
        except Exception as exc:  # NLSNotConvergedException and any other Akantu error
            error = f"increment {k}: {type(exc).__name__}: {exc}"
        converged = error is None and solver.getBool("converged")
        iterations = solver.getInt("nb_iterations")

        f_int = solid.getInternalForce()
        gaps = contact.getGaps()[slave, 0]
        x = X + solid.getDisplacement()
        depth = np.interp(x[slave, 0], x[master, 0], x[master, 1]) - x[slave, 1]
        result["steps"].append({
            "step": k, "delta": delta, "converged": bool(converged), "iterations": iterations,
            "force": finite(f_int[top, 1].sum()),
            "block_base_force": finite(-f_int[base, 1].sum()),
            "max_gap": finite(max(gaps.max(), 0.0)),
            "n_contact": int((gaps > 0).sum()),
            "max_penetration": finite(max(depth.max(), 0.0)),
            "n_penetrating": int((depth > 0).sum()),
        })
        if not converged:
            result["error"] = (f"{error or f'increment {k}: Newton did not converge'} "
                               f"(residual norm {solver.getReal('error'):.3g} after "
                               f"{iterations} iterations)")
            return

    result["converged"] = True
    result["force"] = result["steps"][-1]["force"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mesh", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--epsilon", type=float, required=True)
    parser.add_argument("--delta", type=float, required=True)
    parser.add_argument("--steps", type=int, required=True)
    parser.add_argument("--youngs", type=float, default=1000.0)
    parser.add_argument("--poisson", type=float, default=0.3)
    parser.add_argument("--block-youngs", type=float, help="the block's E (default: --youngs)")
    parser.add_argument("--rigid-master", action="store_true",
                        help="is_master_deformable = false: the block receives no contact force")
    args = parser.parse_args()

    result = {"akantu": None, "epsilon_n": args.epsilon, "epsilon_meaning": MEANING,
              "steps": [], "converged": False, "force": None, "error": None}
    started = time.monotonic()
    try:
        run(args, result)
    except Exception as exc:
        result["error"] = f"{type(exc).__name__}: {exc}\n{traceback.format_exc()}"
    result["seconds"] = round(time.monotonic() - started, 3)
    try:
        Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    except OSError as exc:
        print(f"akantu_penalty: cannot write {args.out}: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
