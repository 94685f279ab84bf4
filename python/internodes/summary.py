"""Typed views of ``Result.summary`` (what ``summary.json`` holds), for editors and type checkers.

At run time the summary is a plain ``dict``; these ``TypedDict`` classes only name its keys and
their types, with what each means (docs/output.md has the file's description)::

    from internodes.summary import Summary
    summary: Summary = result.summary
    reason = summary["contact"]["primary_choice"]["reason"]
"""

from typing import NotRequired, Optional, TypedDict


class _CheckNote(TypedDict, total=False):
    note: str
    """What the figure was compared with, when that is not a node (an agreement check)."""


class Check(_CheckNote):
    """One residual check or accuracy indicator: its figure against its tolerance."""

    name: str
    """e.g. "penetration", "secondary sag", "primary agreement"."""
    value: float
    tolerance: float
    passed: bool
    body: Optional[str]
    """The body of the worst node, where the check is nodal."""
    node_tag: Optional[int]
    """The gmsh tag of the worst node."""


class Coverage(TypedDict, total=False):
    """One source of error in what a user reads, and the indicators that estimated it."""

    error: str
    """"interface coupling", "contact zone resolution" or "bulk discretization"."""
    affects: str
    estimated_by: list[str]
    """The indicators of this run that estimate it (names of `Check`)."""
    not_estimated: str
    """Present when something of it was not estimated: what, and how to estimate it."""


class Solved(TypedDict):
    """The residual checks of the discrete problem (the status is converged only if all pass)."""

    passed: bool
    checks: list[Check]


class Accuracy(TypedDict):
    """The accuracy report: its indicators, and which errors they cover."""

    passed: bool
    indicators: list[Check]
    coverage: list[Coverage]


class PrimaryChoice(TypedDict):
    """Which body carries the multiplier, chosen how and why."""

    mode: str
    """"auto" or "explicit"."""
    reason: str


class TransferChoice(TypedDict):
    """How the secondary's contact force is computed, and why."""

    transfer: str
    """"interpolation", "conservative" or "node-to-facet"."""
    reason: str


class HertzFit(TypedDict):
    """The Hertz ellipse fitted to the primary's contact pressure."""

    a: float
    """Contact radius (3D) or half-width (2D)."""
    p0: float
    """Peak pressure."""
    center: list[float]


class LinearSolvers(TypedDict):
    """The solvers that ran (auto resolved)."""

    body: str
    """"cholesky" or "cg-amg"."""
    interface: str
    """"krylov" (one preconditioned GMRES on the whole coupled system) or "schur"."""
    krylov_failure: Optional[str]
    """Why an auto solve left GMRES for the dense Schur complement, if it did."""
    body_applications: Optional[list[int]]
    """Krylov path: applications of each body's preconditioner block over the whole solve
    (AMG V-cycles with cg-amg bodies), [primary, secondary]."""


class ForcedDisplacement(TypedDict):
    """A force-controlled group ([[body.force]]) at one load step."""

    body: str
    group: str
    component: str
    """"x", "y" or "z"."""
    force: float
    """The prescribed force times the step's factor of its load path."""
    displacement: float
    """The group's displacement along the component: what the force gave."""


class StepFriction(TypedDict):
    """A Coulomb pair's tangential answer at one load step."""

    tangential_force: list[float]
    """The tangential contact force on the primary body: the total contact force less its
    part along the zone's mean normal."""
    normal_force: float
    """The normal contact force on the primary body: minus the total contact force along the
    zone's mean normal."""
    stick_nodes: int
    slip_nodes: int



class _StepPath(TypedDict, total=False):
    path_factors: dict[str, float]
    """Each named load path's factor at this step (only with a [load_path])."""


class StepRecord(_StepPath):
    """How one load step ended (also a row of force_displacement.csv)."""

    step: int
    load_factor: float
    """The factor of the loads, forces and prescribed displacements without a load path."""
    status: str
    iterations: int
    force_primary: list[float]
    force_secondary: list[float]
    force_imbalance: float
    hertz_a: Optional[float]
    hertz_p0: Optional[float]
    forced: list[ForcedDisplacement]
    """Each force-controlled group's force and the displacement it gave."""
    seconds: float
    accurate: bool
    failed_checks: list[str]
    friction: NotRequired[StepFriction]
    """Coulomb pairs only."""


class Contact(TypedDict):
    """The contact record of one pair: status, choices, checks, forces and history of the last
    load step."""

    name: str
    """The pair's name ([contact] name; default "BODY1-BODY2", the bodies in the order
    given)."""
    status: str
    """"converged", "no-contact", "not-solved", "stalled", "unstable", "cycling" or
    "iteration-limit"."""
    primary: str
    secondary: str
    primary_choice: PrimaryChoice
    transfer: TransferChoice
    solved: Solved
    accuracy: Accuracy
    settings: dict[str, object]
    """The [contact] settings used (docs/case-file.md)."""
    linear_solvers: LinearSolvers
    force_primary: list[float]
    """Total contact force on the primary body."""
    force_secondary: list[float]
    force_imbalance: float
    """|F1 + F2| / |F1|."""
    active_primary: int
    active_secondary: int
    max_pressure: float
    max_tangential_traction: float
    hertz_fit: Optional[HertzFit]
    iterations: list[dict[str, object]]
    """The last load step's active-set iterations."""
    steps: list[StepRecord]


class Body(TypedDict):
    """One body: material, sizes, reactions and its solve."""

    name: str
    youngs_modulus: float
    poisson_ratio: float
    num_nodes: int
    num_cells: int
    num_dofs: int
    node_offset: int
    cell_offset: int
    reactions: dict[str, list[float]]
    """The reaction force on each Dirichlet group."""
    solve: dict[str, object]


class _SummaryOptional(TypedDict, total=False):
    contact: Contact
    """Present when the case has one contact pair (a [contact] table, or one [[contact]])."""
    contacts: list[Contact]
    """Present when the case has several contact pairs ([[contact]] tables): each pair's
    record, in the case's order (then `contact` is absent)."""
    peak_memory_mb: float
    """The process's peak resident memory, where Linux reports it."""
    rank_peak_memory_mb: list[float]
    """Each MPI rank's peak memory, in rank order, in a distributed run (`mpirun`); absent
    otherwise (a Python process is one rank)."""


class Summary(_SummaryOptional):
    """What ``summary.json`` holds."""

    case: str
    mesh: str
    dimension: int
    bodies: list[Body]
    timings: list[object]
    ranks: int
    """The number of MPI processes that solved the case: 1 from Python."""
