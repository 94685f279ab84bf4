"""What a validation suite returns to ``run.py``, which writes them all into ``validation/report/``.

A suite is a module with ``run_suite(binary: Path, quick: bool, out_dir: Path) -> SuiteResult``:
``binary`` is the internodes executable, ``quick`` asks for the coarsest levels only (``make test``;
the pass/fail thresholds stay the same), ``out_dir`` is the suite's folder inside the report, where
its PNG figures go (scratch files go under ``validation/build/``).

Every pass/fail figure is a ``compare.Check``: it passes when ``figure <= tolerance``, so errors are
expressed as non-negative numbers (relative errors, or distances in units of the interface
spacing). Figures that are information only (fitted rates, Hertz's force-approach law beside the
reference) go in ``text`` and ``data``, never in ``checks``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import subprocess
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from compare import Check


@dataclass
class Figure:
    """A PNG written by the suite into its ``out_dir``, with the caption the report shows."""

    caption: str
    path: Path


@dataclass
class SuiteResult:
    """One section of the report."""

    title: str
    checks: list[Check] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    text: str = ""
    data: dict = field(default_factory=dict)


@dataclass
class SolveRun:
    """One ``internodes solve``: its combined output, exit status (``"timeout"`` when stopped) and
    wall time."""

    log: str
    exit: int | str
    seconds: float

    def tail(self, lines: int = 3) -> str:
        """The last lines of the log, on one line."""
        return " | ".join(self.log.strip().splitlines()[-lines:])


def run_solve(binary: Path, case: Path, output: Path | None = None, timeout: float | None = None,
              log: Path | None = None, extra: tuple[str, ...] = ()) -> SolveRun:
    """``internodes solve case`` (into ``output`` with ``--output`` when given, whose stale answer files
    are removed first, so that a run that writes nothing is never read as the last one's answer):
    the one way the validation runs the solver. ``extra`` are further flags (``--export-matrices``);
    the log goes to ``log`` when given."""
    command = [str(binary), "solve", str(case), *extra]
    if output is not None:
        command += ["--output", str(output)]
        for stale in ("summary.json", "solution.h5", "force_displacement.csv"):
            (output / stale).unlink(missing_ok=True)
    start = time.perf_counter()
    try:
        result = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
        text, code = result.stdout + result.stderr, result.returncode
    except subprocess.TimeoutExpired as error:
        def decoded(part):
            return part.decode(errors="replace") if isinstance(part, bytes) else (part or "")
        text = f"{decoded(error.stdout)}{decoded(error.stderr)}\ntimeout after {timeout:g} s"
        code = "timeout"
    run = SolveRun(text, code, time.perf_counter() - start)
    if log is not None:
        log.write_text(text)
    return run


GEO = Path(__file__).resolve().parent.parent / "geo"


class MeshFailed(RuntimeError):
    """gmsh could not mesh a geo script (the message ends with gmsh's output)."""


def mesh_geo(script: str, dim: int, parameters: dict, path: Path) -> Path:
    """gmsh ``geo/<script>.geo`` with ``-setnumber`` parameters into ``path`` (MSH 4.1).

    Cached: a stamp next to the mesh records the parameters and a hash of the geo script, so an
    edited script or other parameters mesh again.
    """
    geo = GEO / f"{script}.geo"
    stamp = path.with_suffix(".json")
    key = {"parameters": parameters, "geo_sha256": hashlib.sha256(geo.read_bytes()).hexdigest()}
    if path.is_file() and stamp.is_file() and json.loads(stamp.read_text()) == key:
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    command = ["gmsh", f"-{dim}", str(geo), "-format", "msh41", "-v", "1", "-o", str(path)]
    for name, value in parameters.items():
        command += ["-setnumber", name, str(value)]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0 or not path.is_file():
        raise MeshFailed(f"gmsh {geo.name} {parameters} failed: {(result.stdout + result.stderr)[-400:]}")
    stamp.write_text(json.dumps(key))
    return path


# ---------------------------------------------------------------------------
# The [contact] table of a case file
# ---------------------------------------------------------------------------

def contact_table(bodies: tuple[str, str], surfaces: tuple[str, str], primary: str = "auto",
                  formulation: str = "frictionless", **extra) -> dict:
    """The ``[contact]`` table of a case file (for ``case_toml``).

    ``bodies`` are the two bodies in contact, ``surfaces`` their candidate surfaces in the same
    order, ``primary`` "auto" or one of the two body names (an explicit choice). ``extra`` are
    further keys (``load_steps = [...]``, ``transfer``...).
    """
    if primary != "auto" and primary not in bodies:
        raise ValueError(f"primary '{primary}' is neither 'auto' nor one of the bodies {bodies}")
    return {"bodies": list(bodies), "surfaces": list(surfaces), "primary": primary,
            "formulation": formulation, **extra}


def body_table(name: str, youngs_modulus: float, poisson_ratio: float,
               dirichlet: list[tuple[str, dict]]) -> dict:
    """A ``[[body]]`` table: material and Dirichlet conditions (group, {component: value})."""
    return {"name": name, "youngs_modulus": youngs_modulus, "poisson_ratio": poisson_ratio,
            "dirichlet": [{"group": group, **values} for group, values in dirichlet]}


def case_toml(mesh: Path | str, output: Path | str, contact: dict | None, bodies: list[dict],
              comment: str = "") -> str:
    """A case file: the one writer of the validation's cases (the keys of ``docs/case-file.md``)."""
    case = {"mesh": str(mesh), "output": str(output)}
    if contact is not None:
        case["contact"] = contact
    case["body"] = bodies
    return (f"# {comment}\n" if comment else "") + toml_text(case)


def toml_text(table: dict, prefix: str = "") -> str:
    """A TOML document for nested dicts / lists of dicts / scalars (enough for case files)."""
    def value(v) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (int, float)):
            return repr(v)
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        raise TypeError(f"no TOML form for {v!r}")

    def is_table_array(v) -> bool:
        return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)

    lines = [f"{k} = {value(v)}" for k, v in table.items() if not isinstance(v, dict) and not is_table_array(v)]
    for k, v in table.items():
        if isinstance(v, dict):
            lines += ["", f"[{prefix}{k}]", toml_text(v, f"{prefix}{k}.")]
        elif is_table_array(v):
            for item in v:
                lines += ["", f"[[{prefix}{k}]]", toml_text(item, f"{prefix}{k}.")]
    return "\n".join(lines).strip() + "\n"


def contact_sides(table: dict) -> dict[str, str]:
    """Body name -> candidate surface of a ``[contact]`` table."""
    return dict(zip(table["bodies"], table["surfaces"]))


def group_edges(msh: Path, group: str, dim: int):
    """(node coordinates indexed by gmsh node tag, the distinct edges of the boundary group
    ``group`` as pairs of node tags) of a ``dim``-dimensional mesh; ValueError when it has no such
    group."""
    import gmsh
    import numpy as np

    gmsh.initialize(["gmsh", "-v", "0"])
    try:
        gmsh.open(str(msh))
        tags, coords, _ = gmsh.model.mesh.getNodes()
        x = np.zeros((int(tags.max()) + 1, 3))
        x[tags.astype(int)] = coords.reshape(-1, 3)
        groups = {gmsh.model.getPhysicalName(d, t): (d, t) for d, t in gmsh.model.getPhysicalGroups(dim - 1)}
        if group not in groups:
            raise ValueError(f"{msh}: no physical group '{group}'")
        facets = []
        for entity in gmsh.model.getEntitiesForPhysicalGroup(*groups[group]):
            _, _, nodes = gmsh.model.mesh.getElements(dim - 1, entity)
            facets += [n.astype(int).reshape(-1, dim) for n in nodes]
    finally:
        gmsh.finalize()
    facets = np.concatenate(facets)
    edges = np.concatenate([facets[:, [i, (i + 1) % dim]] for i in range(dim if dim == 3 else 1)])
    return x, np.unique(np.sort(edges, axis=1), axis=0)


def surface_spacing(msh: Path, group: str, dim: int, radius: float) -> float:
    """Mean length of the edges of a surface group with both ends within ``radius`` of the contact axis."""
    import numpy as np

    x, edges = group_edges(msh, group, dim)
    r = np.linalg.norm(x[:, : dim - 1], axis=1)
    near = edges[(r[edges] <= radius).all(axis=1)]
    if len(near) == 0:
        return float("nan")
    return float(np.linalg.norm(x[near[:, 0]] - x[near[:, 1]], axis=1).mean())


def json_safe(value):
    """Replace NaN / inf by None, keys by strings and numpy scalars by Python ones, recursively."""
    import math

    import numpy as np

    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, np.generic):
        return json_safe(value.item())
    return value


# ---------------------------------------------------------------------------
# The solver's two reports in summary.json (contact.solved, contact.accuracy)
# ---------------------------------------------------------------------------

# Residual checks of the discrete problem (contact.solved.checks): all present in every contact run.
SOLVED_CHECKS = ("penetration", "secondary penetration", "tension", "complementarity", "equilibrium")
# Accuracy indicators (contact.accuracy.indicators) present in every contact run; "primary agreement"
# is added by the solver when it makes that second solve, and is then judged like the others.
ACCURACY_INDICATORS = ("secondary sag", "resolution", "force centre")


def solver_reports(contact: dict) -> tuple[dict | None, dict | None]:
    """(solved, accuracy) of a summary.json contact object: ``solved`` is {"passed", "checks": [...]},
    ``accuracy`` {"passed", "indicators": [...]}; either is None when absent (a failed row)."""
    solved = contact.get("solved")
    accuracy = contact.get("accuracy")
    return (solved if isinstance(solved, dict) else None, accuracy if isinstance(accuracy, dict) else None)


def failed_report_names(contact: dict) -> list[str]:
    """Names of the failed residual checks and accuracy indicators (for tables)."""
    solved, accuracy = solver_reports(contact)
    return ([c.get("name") for c in (solved or {}).get("checks", []) if c.get("passed") is not True]
            + [c.get("name") for c in (accuracy or {}).get("indicators", []) if c.get("passed") is not True])


def vouched(contact: dict) -> bool:
    """The solver vouches for its answer: converged (or no contact) and its accuracy report passed,
    and so did every earlier load step (CLI exit code 0)."""
    _, accuracy = solver_reports(contact)
    steps_trusted = all(step.get("status") in ("converged", "no-contact") and step.get("accurate") is True
                        for step in contact.get("steps", []))
    return (contact.get("status") in ("converged", "no-contact")
            and bool(accuracy and accuracy.get("passed") is True) and steps_trusted)


def report_rows(case: str, contact: dict, accuracy_required: tuple[str, ...] = ACCURACY_INDICATORS) -> list[Check]:
    """Two rows, ``solved`` and ``accuracy``: each report present, every named entry present and
    passed, its flags consistent with its figures; figure the largest value / tolerance over the
    entries (tolerance 1). A missing report or entry, or a "passed" flag that contradicts the
    figures, is a failed row (figure NaN, the note says which), never a pass."""
    solved, accuracy = solver_reports(contact)
    return [_report_row("solved", case, solved, "checks", SOLVED_CHECKS),
            _report_row("accuracy", case, accuracy, "indicators", accuracy_required)]


def _report_row(kind: str, case: str, report: dict | None, key: str, required: tuple[str, ...]) -> Check:
    import math

    if report is None:
        return Check(kind, case, math.nan, 1.0, f"summary.json contact.{kind} missing")
    entries = report.get(key) if isinstance(report.get(key), list) else []
    by_name = {c.get("name"): c for c in entries if isinstance(c, dict)}
    missing = [n for n in required if n not in by_name]
    names = list(required) + [n for n in by_name if n not in required]
    ratios, parts = [], []
    for name in names:
        c = by_name.get(name)
        if c is None:
            continue
        try:
            value, tolerance = float(c["value"]), float(c["tolerance"])
        except (KeyError, TypeError, ValueError):
            missing.append(f"{name} (no value / tolerance)")
            continue
        ratio = value / tolerance if tolerance > 0 else math.inf
        ratios.append(ratio)
        where = f" at {c.get('body')} node {c.get('node_tag')}" if c.get("node_tag") is not None else ""
        parts.append(f"{name} {value:.3g} / {tolerance:.3g}{where}{'' if c.get('passed') is True else ' FAILED'}")
    worst = max(ratios, default=math.nan)
    note = "; ".join(parts)
    if missing:
        return Check(kind, case, math.nan, 1.0, f"{kind} report lacks {', '.join(missing)}; {note}")
    flags = report.get("passed") is True and all(by_name[n].get("passed") is True for n in names)
    if flags != (worst <= 1.0):
        return Check(kind, case, math.nan, 1.0, f"{kind}.passed = {report.get('passed')} contradicts its figures; {note}")
    return Check(kind, case, worst, 1.0, note)


def checks_table(checks: list[Check]) -> list[str]:
    """The report's table of ``checks``: one row each, the figure, tolerance, PASS/FAIL and note."""
    return ["", "**Checks**", "", "| check | case | figure | tolerance | result | note |", "|---|---|---|---|---|---|",
            *(f"| {c.check} | {c.case} | {'n/a' if math.isnan(c.figure) else f'{c.figure:.3g}'} | {c.tolerance:.3g} "
              f"| {'PASS' if c.passed else '**FAIL**'} | {c.note} |" for c in checks)]


def standalone(doc: str, names: set[str], run, json_name: str, build: Path, **extra) -> int:
    """A suite run alone (its ``main``): the flags ``--quick``, ``--binary``, ``--cases`` (of
    ``names``) and ``--out``; ``run(binary, quick, out, cases)`` gives its SuiteResult, whose
    text is printed and whose checks and data go to ``out/json_name`` (with ``extra``, and the
    binary when ``extra`` asks for it by ``binary=True``). 0 if every check passed."""
    repo = Path(__file__).resolve().parent.parent
    parser = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="the quick subset only (make test)")
    parser.add_argument("--binary", type=Path, default=repo / "target/release/internodes")
    parser.add_argument("--cases", nargs="+", help="case names (default: all)")
    parser.add_argument("--out", type=Path, default=build / "report")
    args = parser.parse_args()
    unknown = set(args.cases or []) - names
    if unknown:
        parser.error(f"unknown cases {sorted(unknown)}; known: {sorted(names)}")
    result = run(args.binary.resolve(), args.quick, args.out, args.cases)
    print(result.text)
    head = {"binary": str(args.binary)} if extra.pop("binary", False) else {}
    checks = [asdict(c) | {"figure": c.figure if math.isfinite(c.figure) else None, "passed": c.passed}
              for c in result.checks]
    (args.out / json_name).write_text(json.dumps(head | {"checks": checks, "data": result.data} | extra, indent=1))
    return 0 if all(c.passed for c in result.checks) else 1


def run_cases(cases: list, run, describe) -> tuple[list[Check], dict]:
    """Each of ``cases`` in turn: ``run(case)`` gives its checks and its record (which gets its wall
    time, ``wall_seconds``); the progress is printed as ``name: describe(case) ...``, then the
    status (if the record has one), the wall time and the checks that failed. Returns every
    check and the records by case name."""
    checks: list[Check] = []
    records: dict = {}
    for case in cases:
        print(f"  {case.name}: {describe(case)} ...", flush=True)
        start = time.perf_counter()
        case_checks, record = run(case)
        record["wall_seconds"] = time.perf_counter() - start
        checks += case_checks
        records[case.name] = record
        failed = [f"{c.check} ({c.case})" for c in case_checks if not c.passed]
        status = record.get("status", record.get("error"))
        print(f"    {f'{status}, ' if status else ''}{len(case_checks)} checks, {record['wall_seconds']:.1f} s; "
              f"{'all pass' if not failed else 'FAILED: ' + ', '.join(failed)}", flush=True)
    return checks, records
