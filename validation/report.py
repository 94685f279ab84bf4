"""Writes ``validation/report/``: ``README.md`` (tables of every check with its tolerance and
pass/fail, the text and figures of each suite, the machine and versions) and ``results.json``
(every number).

Two kinds of checks, kept apart in the tables and in the exit status of ``run.py``:

* gate checks: properties that hold to round-off or by construction when the code is right
  (FEniCSx cross-checks of matrices and single-body solutions, the body-by-body check of contact
  solutions). One failure fails ``make validate`` and ``make test``.
* targets: the accuracy targets of the contact solver (Hertz, convergence, the rigid-flat
  reference). They are reported with their figures, met or missed; a miss is a finding about
  the method and the meshes, stated plainly, and does not fail the run.
"""

from __future__ import annotations

import datetime
import json
import math
import os
import platform
import subprocess
from dataclasses import asdict
from pathlib import Path

from compare import Check
from suite import SuiteResult


# The commit the run started from (set by run.py before it writes anything, so that files the run
# itself writes, such as the regression bands, do not mark the report "-dirty").
COMMIT: str | None = None


def machine() -> dict:
    """Machine and versions, for the report header."""
    def command(*args: str) -> str:
        try:
            return subprocess.run(args, capture_output=True, text=True, timeout=60).stdout.strip()
        except OSError:
            return "not found"

    cpu = "unknown"
    try:
        cpu = next(line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                   if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    try:
        import dolfinx
        dolfinx_version = dolfinx.__version__
    except ImportError:
        dolfinx_version = "not importable"
    repo = Path(__file__).resolve().parent.parent
    return {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "machine": f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}",
        "os": command("sh", "-c", ". /etc/os-release && echo $PRETTY_NAME"),
        "commit": COMMIT or command("git", "-C", str(repo), "describe", "--always", "--dirty"),
        "rustc": command("rustc", "--version"),
        "dolfinx": dolfinx_version,
        "gmsh": command("gmsh", "--version") or command("sh", "-c", "gmsh --version 2>&1"),
        "python": platform.python_version(),
    }


def _row(c: Check) -> str:
    figure = "n/a" if math.isnan(c.figure) else f"{c.figure:.3g}"
    verdict = "PASS" if c.passed else "**FAIL**"
    return f"| {c.check} | {c.case} | {figure} | {c.tolerance:g} | {verdict} | {c.note} |"


def _table(checks: list[Check]) -> list[str]:
    return ["| check | case | figure | tolerance | result | note |", "|---|---|---|---|---|---|",
            *map(_row, checks)]


def _figure(c: Check) -> str:
    return "n/a" if math.isnan(c.figure) else f"{c.figure:.3g}"


def headline(gate: list[SuiteResult], targets: list[SuiteResult]) -> list[str]:
    """The report's headline table: one row per gate suite (checks passed, the
    largest figure relative to its tolerance) and one per kind of target (met out of run, the
    worst case and every missed case)."""
    lines = ["| suite | check | result | worst figure (case) | tolerance | missed |", "|---|---|---|---|---|---|"]
    for s in gate:
        if not s.checks:
            continue
        worst = max(s.checks, key=lambda c: math.inf if math.isnan(c.figure) else
                    (c.figure / c.tolerance if c.tolerance > 0 else c.figure))
        passed = sum(c.passed for c in s.checks)
        lines.append(f"| {s.title} | all (gate) | {passed} of {len(s.checks)} passed | {_figure(worst)} "
                     f"({worst.check}, {worst.case}) | {worst.tolerance:g} | "
                     f"{', '.join(f'{c.check}: {c.case}' for c in s.checks if not c.passed) or '-'} |")
    for s in targets:
        kinds: dict[str, list[Check]] = {}
        for c in s.checks:
            kinds.setdefault(c.check, []).append(c)
        for kind, checks in kinds.items():
            worst = max(checks, key=lambda c: math.inf if math.isnan(c.figure) else c.figure)
            missed = [c for c in checks if not c.passed]
            met = len(checks) - len(missed)
            lines.append(f"| {s.title} | {kind} | {met} of {len(checks)} met | {_figure(worst)} ({worst.case}) "
                         f"| {worst.tolerance:g} | "
                         f"{'; '.join(f'{c.case} ({_figure(c)})' for c in missed) or '-'} |")
    return lines


def write(report_dir: Path, gate: list[SuiteResult], targets: list[SuiteResult], command: str) -> dict:
    """Writes README.md and results.json into ``report_dir``; returns the summary counts."""
    report_dir.mkdir(parents=True, exist_ok=True)
    info = machine()
    gate_checks = [c for s in gate for c in s.checks]
    target_checks = [c for s in targets for c in s.checks]
    counts = {
        "gate_passed": sum(c.passed for c in gate_checks), "gate_failed": sum(not c.passed for c in gate_checks),
        "targets_met": sum(c.passed for c in target_checks),
        "targets_missed": sum(not c.passed for c in target_checks),
    }
    lines = [
        "# Validation report",
        "",
        f"Written by `{command}`; do not edit by hand.",
        "",
        "| item | value |", "|---|---|",
        *[f"| {k} | {v} |" for k, v in info.items()],
        "",
        f"**Gate checks:** {counts['gate_passed']} passed, {counts['gate_failed']} failed. "
        f"**Targets:** {counts['targets_met']} met, {counts['targets_missed']} missed.",
        "",
        "Gate checks hold to round-off when the code is right; one failure fails the run. Targets are "
        "the accuracy targets of the contact solver; each is reported with its figure, met or missed, "
        "and a miss is explained in its section.",
        "",
        "## Headline",
        "",
        *headline(gate, targets),
        "",
        "## Targets",
        "",
        *_table(target_checks),
        "",
        "## Gate checks",
        "",
        *_table(gate_checks),
        "",
    ]
    for s in targets + gate:
        lines += [f"## {s.title}", ""]
        if s.text:
            lines += [s.text, ""]
        for figure in s.figures:
            relative = os.path.relpath(figure.path, report_dir)
            lines += [f"![{figure.caption}]({relative})", "", f"*{figure.caption}*", ""]
    (report_dir / "README.md").write_text("\n".join(lines))

    def checks_json(checks: list[Check]) -> list[dict]:
        return [asdict(c) | {"figure": None if math.isnan(c.figure) else c.figure, "passed": c.passed}
                for c in checks]

    results = {
        "machine": info, **counts,
        "suites": [{"title": s.title, "kind": kind, "checks": checks_json(s.checks), "data": s.data}
                   for kind, suites in (("gate", gate), ("target", targets)) for s in suites],
    }
    (report_dir / "results.json").write_text(json.dumps(results, indent=1, default=str) + "\n")
    return counts


HEADLINE_START = "<!-- validation headline: written by make validate (validation/report.py) -->"
HEADLINE_END = "<!-- end of validation headline -->"


def update_readme(readme: Path, counts: dict) -> bool:
    """Replaces the block between the headline markers of ``readme`` with this run's counts and a
    link to the report's headline table; False (README untouched) when the markers are
    missing."""
    text = readme.read_text()
    start, end = text.find(HEADLINE_START), text.find(HEADLINE_END)
    if start < 0 or end < start:
        return False
    block = [HEADLINE_START, "",
             f"Gate checks: {counts['gate_passed']} passed, {counts['gate_failed']} failed. "
             f"Targets: {counts['targets_met']} met, {counts['targets_missed']} missed "
             f"({datetime.date.today().isoformat()}; each suite's row, with its worst figure and "
             "every missed case, in [the report's headline](validation/report/README.md#headline)).",
             ""]
    readme.write_text(text[:start] + "\n".join(block) + "\n" + text[end:])
    return True
