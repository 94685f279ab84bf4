"""Type stubs of the native module (python/src/lib.rs)."""

from os import PathLike
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union, final

import numpy as np
import numpy.typing as npt

from .summary import Contact, ForcedDisplacement, StepFriction, Summary

__all__ = [
    "__version__",
    "BodyResult",
    "Cancel",
    "Cancelled",
    "Case",
    "ContactResult",
    "InputError",
    "Mesh",
    "NotSolvedError",
    "Result",
    "SolveError",
    "Step",
    "Study",
    "SurfaceResult",
    "WriteError",
    "_restore_case",
    "_restore_generated_mesh",
    "_restore_model_mesh",
    "solve",
    "study",
]

_StrPath = Union[str, PathLike[str]]

__version__: str
"""The version of the solver the module was built from."""

class InputError(ValueError):
    """A case or a mesh that cannot be used; the message is the command line's."""

class SolveError(RuntimeError):
    """A solve that failed: a body's linear solve, or the contact solve."""

class NotSolvedError(RuntimeError):
    """Raised by Result.raise_for_status when the exit code would not be 0."""

class WriteError(OSError):
    """The result files could not be written."""

class Cancelled(Exception):
    """Raised by solve() when its Cancel token was cancelled."""

@final
class Cancel:
    """A token that cancels the solves given it (solve(case, cancel=token)) from another thread,
    at their next load step, active-set iteration or coupled GMRES iteration. A cancelled
    token stays cancelled."""

    def __init__(self) -> None: ...
    def cancel(self) -> None:
        """Stops every solve holding this token at its next safe point."""
    @property
    def cancelled(self) -> bool:
        """Whether cancel() was called."""

@final
class Case:
    """A case: bodies, materials, boundary conditions, loads and contact settings, with the keys
    of a case file and the same checks."""

    @staticmethod
    def from_toml(path: _StrPath) -> Case:
        """Reads a case file; relative paths in it are relative to its folder."""
    @staticmethod
    def from_dict(
        table: Mapping[str, Any], name: str = "case", folder: Optional[_StrPath] = None
    ) -> Case:
        """A case from a dict with the case file's keys ("contact": a dict, or a list of dicts
        for several pairs); `mesh` may be left out when a Mesh is passed to solve(). Messages
        name it "case 'NAME' (from a dict)". Numbers may be NumPy values, Fractions or Decimals
        (the nearest float); NaN and infinities are refused, naming the key. Relative paths are
        relative to `folder` (default: the current one)."""
    @property
    def path(self) -> Path:
        """The case file, or the name given to from_dict."""
    @property
    def mesh(self) -> Optional[Path]:
        """The mesh the case names, or None."""
    @property
    def bodies(self) -> list[str]:
        """The bodies' names, in the case's order."""
    @property
    def load_steps(self) -> list[float]:
        """The contact solve's load factors ([1.0] unless the case lists steps); with a
        [load_path], those of the entries without `path` (1.0 at each step unless the case
        lists steps)."""
    @property
    def load_path(self) -> dict[str, list[float]]:
        """The case's [load_path]: each named path's factors, one per load step (empty
        without one)."""
    @property
    def pairs(self) -> list[str]:
        """The contact pairs' names, in the case's order ([contact] name, default
        "BODY1-BODY2"; empty without contact)."""

@final
class Mesh:
    """Bodies (physical surfaces in 2D, volumes in 3D) with their boundary and point groups."""

    @staticmethod
    def from_msh(path: _StrPath) -> Mesh:
        """Reads a gmsh MSH 4.1 file (ASCII or binary)."""
    @staticmethod
    def from_geo(path: _StrPath, parameters: Optional[Mapping[str, float]] = None) -> Mesh:
        """Meshes a .geo script with the gmsh program (`parameters`: its -setnumber values,
        checked as a case's geo_parameters: a name the script does not use is refused)."""
    @staticmethod
    def from_gmsh(model: Optional[str] = None) -> Mesh:
        """The meshed current model of the gmsh Python module (or the model named `model`),
        read through gmsh's API without a file."""
    @property
    def path(self) -> Path:
        """The file or model the mesh came from."""
    @property
    def dim(self) -> int:
        """2 or 3."""
    @property
    def bodies(self) -> list[str]: ...
    @property
    def groups(self) -> list[str]:
        """The names of every physical group."""
    @property
    def num_nodes(self) -> dict[str, int]:
        """Each body's number of nodes, by name."""
    @property
    def num_cells(self) -> dict[str, int]:
        """Each body's number of cells (triangles in 2D, tetrahedra in 3D), by name."""

@final
class SurfaceResult:
    """Interface fields on a body's contact candidate surface (k nodes)."""

    nodes: npt.NDArray[np.uint64]
    """(k,) body-local node index of each surface node."""
    pressure: npt.NDArray[np.float64]
    """(k,) contact pressure, positive in compression."""
    mean_pressure: npt.NDArray[np.float64]
    """(k,) normal contact force over the node's area."""
    traction: npt.NDArray[np.float64]
    """(k, dim) contact traction."""
    gap: npt.NDArray[np.float64]
    """(k,) signed distance to the other body, deformed; negative inside it."""
    active: npt.NDArray[np.bool_]
    """(k,) whether the node is in contact."""

@final
class BodyResult:
    """One body's fields: n nodes in the body's local numbering, m cells. The arrays are
    read-only."""

    name: str
    coordinates: npt.NDArray[np.float64]
    """(n, dim) node coordinates."""
    node_tags: npt.NDArray[np.uint64]
    """(n,) gmsh node tags."""
    displacement: npt.NDArray[np.float64]
    """(n, dim) displacement."""
    cells: npt.NDArray[np.uint64]
    """(m, dim + 1) cell connectivity, local node indices."""
    cell_tags: npt.NDArray[np.uint64]
    """(m,) gmsh element tags."""
    strain: npt.NDArray[np.float64]
    """(m, 3, 3) strain per cell."""
    stress: npt.NDArray[np.float64]
    """(m, 3, 3) Cauchy stress per cell."""
    von_mises: npt.NDArray[np.float64]
    """(m,) von Mises stress per cell."""
    surfaces: dict[str, SurfaceResult]
    """Its contact surface in each contact pair it is in, by pair name (in the case's order;
    empty for a body in no pair)."""
    @property
    def surface(self) -> Optional[SurfaceResult]:
        """The contact surface of a body in one contact pair, None for a body in none; a body
        in several pairs raises ValueError (use surfaces[pair])."""

@final
class Step:
    """How one load step ended (the library's record of it). Status, accuracy verdict, failed
    checks, forces and Hertz fit are this step's own; the accuracy report's details and the
    iteration history are kept for the last step only (Result.summary["contact"], or the
    pair's ContactResult.summary)."""

    step: int
    """1, 2, ... in the order solved."""
    load_factor: float
    """The factor of the loads, forces and prescribed displacements without a load path."""
    path_factors: dict[str, float]
    """Each named load path's factor at this step (empty without a [load_path])."""
    status: str
    """This step's contact status ("converged", "not-solved", ...)."""
    solved: bool
    """Whether the status is a solution ("converged" or "no-contact")."""
    accurate: bool
    """Whether this step's accuracy report passed."""
    failed_checks: list[str]
    """The checks this step failed, by name."""
    iterations: int
    force_primary: npt.NDArray[np.float64]
    """(dim,) total contact force on the primary body."""
    force_secondary: npt.NDArray[np.float64]
    force_imbalance: float
    hertz_a: Optional[float]
    hertz_p0: Optional[float]
    forced: list[ForcedDisplacement]
    """Each force-controlled group's force at this step and the displacement it gave."""
    friction: Optional[StepFriction]
    """A Coulomb pair's tangential answer at this step; None for the other laws."""
    seconds: float

@final
class ContactResult:
    """One contact pair's result (Result.contacts[name])."""

    @property
    def name(self) -> str:
        """The pair's name ([contact] name, default "BODY1-BODY2")."""
    @property
    def status(self) -> str:
        """This pair's contact status ("converged", "no-contact", "iteration-limit", ...)."""
    @property
    def primary(self) -> str:
        """The body that carries the multiplier."""
    @property
    def secondary(self) -> str:
        """The other body."""
    @property
    def solved(self) -> bool:
        """This pair's contact problem solved at every load step."""
    @property
    def accurate(self) -> bool:
        """Solved, and its accuracy report passed at every load step."""
    @property
    def exit_code(self) -> int:
        """The command line's exit status were this the only pair: 0, 2 or 3."""
    @property
    def steps(self) -> list[Step]:
        """One Step per load step solved, in order: this pair's status, forces, accuracy."""
    @property
    def summary(self) -> Contact:
        """This pair's record of summary.json (its "contact", or its entry of "contacts")."""

@final
class Result:
    """A solved case."""

    @property
    def summary(self) -> Summary:
        """What summary.json holds (a new dict at each access; its keys typed in
        internodes.summary)."""
    @property
    def status(self) -> Optional[str]:
        """The contact status ("converged", "no-contact", "iteration-limit", ...), or None when
        the case has no contact. With several pairs, the worst pair's: the first pair whose
        status is not a solution, else "converged" if any pair converged, else "no-contact"."""
    @property
    def contacts(self) -> dict[str, ContactResult]:
        """Each contact pair's result by name, in the case's order (empty without contact)."""
    @property
    def solved(self) -> bool:
        """Every body solved and the contact problem, if any, solved."""
    @property
    def accurate(self) -> bool:
        """Solved, and the accuracy report passed."""
    @property
    def exit_code(self) -> int:
        """The command line's exit status, the worst load step's: 0 solved, 2 not solved, 3
        solved but inaccurate."""
    def raise_for_status(self) -> None:
        """Raises NotSolvedError unless every load step was solved and passed its accuracy
        report (exit_code 0), with the command line's message, which names the failed steps."""
    @property
    def steps(self) -> list[Step]:
        """One Step per load step solved, in order (empty without contact). With several
        contact pairs it raises ValueError: use contacts[name].steps."""
    @property
    def bodies(self) -> dict[str, BodyResult]:
        """Each body's fields at the last load step by name."""
    def step_bodies(self, k: int) -> dict[str, BodyResult]:
        """Each body's fields at load step k + 1 (that of steps[k]; negative k counts from the
        last) by name; IndexError beyond the steps solved."""
    def write(self, folder: _StrPath, *, overwrite: bool = False) -> Path:
        """Writes the command line's result files into `folder` and returns it; a folder that
        holds results already raises FileExistsError unless overwrite=True."""

def solve(
    case: Case,
    mesh: Optional[Mesh] = None,
    *,
    cancel: Optional[Cancel] = None,
    threads: Optional[int] = None,
) -> Result:
    """Solves `case` on `mesh` or on the mesh the case names, without holding the GIL.

    Raises InputError for a case or mesh that cannot be used and SolveError when a solve fails;
    a contact problem not solved (or inaccurate) is a Result with that status. Ctrl-C stops the
    solve within about a second with KeyboardInterrupt; `cancel` stops it from another thread
    with Cancelled. `threads`: the solver's threads, in a pool of this solve's own (default: the
    cores, or RAYON_NUM_THREADS); the answer does not depend on it."""


@final
class Study:
    """A finished mesh refinement study (see docs/study.md)."""

    @property
    def summary(self) -> dict[str, Any]:
        """What study.json holds: levels, estimates with their flags, exit status."""
    @property
    def parameter(self) -> str:
        """The gmsh parameter the study varied."""
    @property
    def values(self) -> npt.NDArray[np.float64]:
        """(n,) the parameter's values, in the order given."""
    @property
    def h(self) -> npt.NDArray[np.float64]:
        """(n,) each level's measured spacing."""
    @property
    def quantities(self) -> dict[str, npt.NDArray[np.float64]]:
        """Each quantity's (n,) values by key (force, a, p0, max_pressure); NaN where none."""
    @property
    def estimates(self) -> dict[str, dict[str, Any]]:
        """Each quantity's estimate by key, as in study.json."""
    @property
    def exit_code(self) -> int:
        """The worst level's exit status: 0, 2 (a level not solved) or 3 (inaccurate)."""
    @property
    def folder(self) -> Path:
        """The study's folder."""

def study(
    case: Case,
    parameter: str,
    values: Sequence[float],
    output: Optional[_StrPath] = None,
) -> Study:
    """Solves `case` (its mesh a .geo) once per value of the gmsh parameter `parameter` and
    estimates each contact quantity's discretization error (observed order, Richardson
    extrapolation, GCI), writing the files of `internodes study` into `output`."""

# What pickles of cases and meshes are read back with (not for direct use).
def _restore_case(
    text: str, name: str, folder: _StrPath, names_mesh: bool, from_dict: bool
) -> Case: ...
def _restore_generated_mesh(geo: _StrPath, bytes: bytes) -> Mesh: ...
def _restore_model_mesh(arrays: Mapping[str, Any]) -> Mesh: ...
