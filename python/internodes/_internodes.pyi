"""Type stubs of the native module (python/src/lib.rs)."""

from os import PathLike
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union, final

import numpy as np
import numpy.typing as npt

__all__ = [
    "BodyResult",
    "Case",
    "InputError",
    "Mesh",
    "NotSolvedError",
    "Result",
    "SolveError",
    "Study",
    "SurfaceResult",
    "WriteError",
    "solve",
    "study",
]

_StrPath = Union[str, PathLike[str]]

class InputError(ValueError):
    """A case or a mesh that cannot be used; the message is the command line's."""

class SolveError(RuntimeError):
    """A solve that failed: a body's linear solve, or the contact solve."""

class NotSolvedError(RuntimeError):
    """Raised by Result.raise_for_status when the exit code would not be 0."""

class WriteError(OSError):
    """The result files could not be written."""

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
        """A case from a dict with the case file's keys; `mesh` may be left out when a Mesh is
        passed to solve(). Relative paths are relative to `folder` (default: the current one)."""
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
        """The contact solve's load factors ([1.0] unless the case lists steps)."""

@final
class Mesh:
    """Bodies (physical surfaces in 2D, volumes in 3D) with their boundary and point groups."""

    @staticmethod
    def from_msh(path: _StrPath) -> Mesh:
        """Reads a gmsh MSH 4.1 file (ASCII or binary)."""
    @staticmethod
    def from_geo(path: _StrPath, parameters: Optional[Mapping[str, float]] = None) -> Mesh:
        """Meshes a .geo script with the gmsh program (`parameters`: its -setnumber values)."""
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
    """One body's fields: n nodes in the body's local numbering, m cells."""

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
    surface: Optional[SurfaceResult]
    """The contact surface's fields in contact runs, else None."""

@final
class Result:
    """A solved case."""

    @property
    def summary(self) -> dict[str, Any]:
        """What summary.json holds (a new dict at each access)."""
    @property
    def status(self) -> Optional[str]:
        """The contact status ("converged", "no-contact", "iteration-limit", ...), or None when
        the case has no contact."""
    @property
    def solved(self) -> bool:
        """Every body solved and the contact problem, if any, solved."""
    @property
    def accurate(self) -> bool:
        """Solved, and the accuracy report passed."""
    @property
    def exit_code(self) -> int:
        """The command line's exit status: 0 solved, 2 not solved, 3 solved but inaccurate."""
    def raise_for_status(self) -> None:
        """Raises NotSolvedError, with the command line's message, unless exit_code is 0."""
    @property
    def bodies(self) -> dict[str, BodyResult]:
        """Each body's fields by name."""
    def write(self, folder: _StrPath) -> Path:
        """Writes the command line's result files into `folder` and returns it."""

def solve(case: Case, mesh: Optional[Mesh] = None) -> Result:
    """Solves `case` on `mesh` or on the mesh the case names, without holding the GIL.

    Raises InputError for a case or mesh that cannot be used and SolveError when a solve fails;
    a contact problem not solved (or inaccurate) is a Result with that status."""

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
