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

from dataclasses import dataclass, field
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
