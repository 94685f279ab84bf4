#!/usr/bin/python3
"""Refinement study suite: ``internodes study`` on six geo/ contact cases, three levels each, and
its extrapolated contact radius and peak pressure against Hertz where Hertz applies.

Cases (E = 1000, nu = 0.3 unless said; the upper body's support pushed down by delta and held
laterally, the lower body's base clamped; one load step; the curved body primary, the punch case
"auto"):

* ``hemisphere_on_block`` (3D Hertz, R = 1, delta = 0.01): the contact-zone size h_c = 0.03,
  0.015, 0.0075 with the far field fixed (as the Hertz suite refines it);
* ``half_disc_on_block`` (2D Hertz, R = 1, delta = 0.02): level = 0, 1, 2 (every size halves);
* ``half_disc_on_big_block``: the same on a block four times wider and deeper (W = H = 8 R): the
  size of the block is the one change, to tell its effect from the discretization's;
* ``half_disc_in_groove`` (2D, a disc R = 1 in a concave groove R_g = 3: Hertz with the effective
  radius 1/R = 1/1 - 1/3, R = 1.5; delta = 0.02): level = 0, 1, 2;
* ``half_disc_in_big_groove``: a groove in a block W = H = 8 R; the groove must be wider than
  the block (R_g > W), so R_g = 9 (R_eff = 1.125): a larger block, but also another groove;
* ``punch_2d`` (a flat punch of half-width 0.25, E = 1e6, on the block, delta = 0.01; sharp
  corners): level = 0, 1, 2. No Hertz: the pressure is singular at the corners, so the peak
  pressure has no limit and the "Hertz fit" of a flat pressure is no contact radius.

For each quantity ``internodes study`` gives the observed order p (Celik et al. 2008, from the
three levels), the Richardson extrapolation phi_ext and GCI_fine (Fs = 1.25) with its flags
(``docs/study.md``). Against Hertz, for a and p0 of the three Hertz cases: Hertz's value at the
extrapolated force P_ext (``hertz_theory.contact``), and the uncertainty

    U = sqrt((GCI_fine,q |q1|)^2 + (k q_H GCI_fine,P)^2),   k = 1/2 (2D), 1/3 (3D)

(q's own GCI band and the GCI of the force carried into q_H, which goes as P^k). Target row
``Hertz a bracketed`` / ``Hertz p0 bracketed``: figure |q_ext - q_H(P_ext)| / U, tolerance 1
(Hertz inside the extrapolation +- U). A sequence not in its asymptotic range (a flag) has no
trustworthy U; its row is reported with the flags. The bodies are not half-spaces: Hertz carries a
modelling error of order a / (body size) and (a / R)^2 that no refinement removes, and the GCI
bounds the discretization error only, so a miss says the two differ by more than the
discretization, not that either is wrong.

``--quick`` (``make test``) does not run the suite: a study needs three levels.

The figures are ratios of small differences (U is a fraction of a percent of q), which any change
of the solver moves by more than run.py's regression bands allow: the suite opts out of them
(``REGRESSION_BANDS``), and its rows stay targets.

Usage:  /usr/bin/python3 validation/refinement_study.py [--binary PATH] [--out DIR]

Case files and the per-level solutions go to validation/build/refinement_study/; each case's
study.{json,csv,md,png} is copied to --out (default validation/report/refinement_study/<case>/).
A full run takes 30 to 45 s on 2 shared cores, most of it the finest hemisphere level.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

VALIDATION = Path(__file__).resolve().parent
REPO = VALIDATION.parent

import hertz_theory  # noqa: E402
from compare import Check  # noqa: E402
from suite import Figure, SuiteResult, body_table, contact_table, toml_text  # noqa: E402

BUILD = VALIDATION / "build" / "refinement_study"
STUDY_FILES = ("study.json", "study.csv", "study.md", "study.png")
E, NU = 1000.0, 0.3
# run.py: no regression bands on this suite's figures (see the module's doc).
REGRESSION_BANDS = False


@dataclass
class StudyCase:
    """One geo/ case of the suite and the parameter it is refined by."""

    name: str
    dim: int
    bodies: tuple[str, str]  # upper (pushed down), lower (clamped)
    surfaces: tuple[str, str]
    supports: tuple[str, str]
    primary: str
    delta: float
    parameter: str
    values: tuple
    geo_parameters: dict
    hertz_radius: float | None  # effective radius; None: Hertz does not apply
    upper_modulus: float = E
    what: str = ""
    script: str = ""  # the geo/ script, when not the case's name

    @property
    def geo(self) -> str:
        return self.script or self.name

    def case_text(self, output: Path) -> str:
        """The case file: geo/<name>.geo with its parameters, one load step."""
        down = {"ux": 0.0, "uy": -self.delta} if self.dim == 2 else {"ux": 0.0, "uy": 0.0, "uz": -self.delta}
        clamped = {"ux": 0.0, "uy": 0.0, **({"uz": 0.0} if self.dim == 3 else {})}
        table = {
            "mesh": str(REPO / "geo" / f"{self.geo}.geo"),
            "output": str(output),
            "geo_parameters": self.geo_parameters,
            "contact": contact_table(self.bodies, self.surfaces, self.primary),
            "body": [body_table(self.bodies[0], self.upper_modulus, NU, [(self.supports[0], down)]),
                     body_table(self.bodies[1], E, NU, [(self.supports[1], clamped)])],
        }
        return f"# refinement_study.py: {self.name}, {self.what}\n" + toml_text(table)


FAR_2D = {"r_c": 0.2, "h_far": 0.5, "d_far": 2.0, "h_c": 0.025}
CASES = (
    StudyCase("hemisphere_on_block", 3, ("sphere", "block"), ("sphere_contact", "block_contact"),
              ("sphere_top", "block_base"), "sphere", 0.01, "h_c", (0.03, 0.015, 0.0075),
              {"r_c": 0.16, "h_far": 0.5, "d_far": 1.0}, 1.0, what="3D Hertz, h_c halving, far field fixed"),
    StudyCase("half_disc_on_block", 2, ("disc", "block"), ("disc_contact", "block_contact"),
              ("disc_top", "block_base"), "disc", 0.02, "level", (0, 1, 2), FAR_2D, 1.0,
              what="2D Hertz, every size halving"),
    StudyCase("half_disc_on_big_block", 2, ("disc", "block"), ("disc_contact", "block_contact"),
              ("disc_top", "block_base"), "disc", 0.02, "level", (0, 1, 2), {**FAR_2D, "W": 8.0, "H": 8.0}, 1.0,
              what="2D Hertz as above on a block 4 times wider and deeper (W = H = 8 R)",
              script="half_disc_on_block"),
    StudyCase("half_disc_in_groove", 2, ("disc", "block"), ("disc_contact", "block_contact"),
              ("disc_top", "block_base"), "disc", 0.02, "level", (0, 1, 2), FAR_2D, 1.5,
              what="2D Hertz in a concave groove (R_eff = 1.5), every size halving"),
    StudyCase("half_disc_in_big_groove", 2, ("disc", "block"), ("disc_contact", "block_contact"),
              ("disc_top", "block_base"), "disc", 0.02, "level", (0, 1, 2),
              {**FAR_2D, "W": 8.0, "H": 8.0, "R_g": 9.0}, 1.125, script="half_disc_in_groove",
              what="2D Hertz in a wider groove (R_g = 9, R_eff = 1.125) of a block W = H = 8 R"),
    StudyCase("punch_2d", 2, ("punch", "block"), ("punch_contact", "block_contact"),
              ("punch_top", "block_base"), "auto", 0.01, "level", (0, 1, 2), {}, None, upper_modulus=1.0e6,
              what="2D flat punch with sharp corners, 1000 times stiffer than the block"),
)


def run_study(binary: Path, case: StudyCase) -> tuple[dict, float, str]:
    """``internodes study`` of one case into build/; returns study.json, the wall time and the
    study's stderr tail (empty when it succeeded)."""
    folder = BUILD / case.name
    shutil.rmtree(folder / "study", ignore_errors=True)  # never read a stale study
    folder.mkdir(parents=True, exist_ok=True)
    case_file = folder / "case.toml"
    case_file.write_text(case.case_text(folder / "out"))
    values = ",".join(str(v) for v in case.values)
    # From the repository, with relative paths: the study's files name the case without the machine's folders.
    command = [str(binary.resolve()), "study", str(case_file.relative_to(REPO)), "--parameter",
               f"{case.parameter}={values}", "--output", str((folder / "study").relative_to(REPO)), "--quiet"]
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, cwd=REPO)
    seconds = time.perf_counter() - start
    study_json = folder / "study" / "study.json"
    if not study_json.is_file():
        return {}, seconds, " | ".join((done.stdout + done.stderr).strip().splitlines()[-3:])
    return json.loads(study_json.read_text()), seconds, ""


def estimate(study: dict, key: str) -> dict | None:
    """The estimate of quantity ``key`` in a study.json (None when it has none)."""
    return next((q.get("estimate") for q in study.get("estimates", []) if q["key"] == key), None)


def hertz_rows(case: StudyCase, study: dict) -> list[dict]:
    """For a and p0: the extrapolation, Hertz at the extrapolated force, U and the figure."""
    force, rows = estimate(study, "force"), []
    e_star = hertz_theory.contact_modulus([(E, NU), (case.upper_modulus, NU)])
    k = 0.5 if case.dim == 2 else 1.0 / 3.0
    for key in ("a", "p0"):
        q = estimate(study, key)
        row = {"quantity": key, "finest": q["phi"][0] if q else math.nan}
        if not (q and force and q.get("extrapolated") is not None and force.get("extrapolated") is not None):
            rows.append(row | {"figure": math.nan, "flags": (q or {}).get("flags", []) + (force or {}).get("flags", [])})
            continue
        hertz = hertz_theory.contact(force["extrapolated"], case.hertz_radius, e_star, case.dim)[key]
        u = math.hypot(q["gci_fine"] * abs(q["phi"][0]), k * hertz * force["gci_fine"])
        rows.append(row | {"extrapolated": q["extrapolated"], "hertz": hertz, "u": u, "p": q["order"],
                           "figure": abs(q["extrapolated"] - hertz) / u if u > 0 else math.inf,
                           "finest_error": q["phi"][0] / hertz - 1, "flags": q["flags"] + force["flags"]})
    return rows


def hertz_table(rows: list[dict]) -> list[str]:
    """The Hertz comparison of one case as Markdown."""
    lines = ["| quantity | finest q1 | q1 / q_H - 1 | p | extrapolated | Hertz at P_ext | U | "
             "\\|q_ext - q_H\\| / U | bracketed | flags (q, force) |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        def g(name, fmt=".5g"):
            value = r.get(name)
            return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else format(value, fmt)
        bracketed = "yes" if r["figure"] <= 1 else ("no" if math.isfinite(r["figure"]) else "-")
        lines.append(f"| {r['quantity']} | {g('finest')} | {g('finest_error', '+.4f')} | {g('p', '.2f')} | "
                     f"{g('extrapolated')} | {g('hertz')} | {g('u', '.2g')} | {g('figure', '.3g')} | {bracketed} | "
                     f"{', '.join(r['flags']) or 'none'} |")
    return lines


def case_section(case: StudyCase, study: dict, seconds: float, out_dir: Path) -> tuple[list[str], list[Check], list[Figure]]:
    """One case's text (its study.md tables, the Hertz comparison), checks and figure."""
    lines = [f"### {case.name}", "", f"{case.what}; `--parameter {case.parameter}="
             f"{','.join(map(str, case.values))}`; wall time of the study {seconds:.0f} s.", ""]
    md = (BUILD / case.name / "study" / "study.md").read_text().splitlines()
    lines += md[2:]  # without the title, which names the build folder
    checks, figures = [], []
    target = out_dir / case.name
    target.mkdir(parents=True, exist_ok=True)
    for name in STUDY_FILES:
        shutil.copy(BUILD / case.name / "study" / name, target / name)
    figures.append(Figure(f"{case.name}: each quantity against the measured spacing h; the cross at h = 0 is "
                          "the Richardson extrapolation, the bar the finest level's GCI band", target / "study.png"))
    if case.hertz_radius is not None:
        rows = hertz_rows(case, study)
        lines += ["Against Hertz (effective radius "
                  f"{case.hertz_radius:g}) at the extrapolated force:", "", *hertz_table(rows), ""]
        for r in rows:
            note = (f"q_ext {r.get('extrapolated', math.nan):.5g}, q_H(P_ext) {r.get('hertz', math.nan):.5g}, "
                    f"U {r.get('u', math.nan):.2g}; flags: {', '.join(r['flags']) or 'none'}")
            checks.append(Check(f"Hertz {r['quantity']} bracketed", case.name, r["figure"], 1.0, note))
    return lines, checks, figures


def run_suite(binary: Path, quick: bool, out_dir: Path) -> SuiteResult:
    """The suite for ``run.py``: every case's study, its tables and the Hertz targets."""
    title = "Refinement study: observed order, Richardson extrapolation and GCI against Hertz"
    if quick:
        return SuiteResult(title=title, text="Not run by `--quick`: a refinement study needs three levels.")
    text = [__doc__.split("Usage:")[0].split("\n", 2)[2].strip(), ""]
    checks, figures, data = [], [], {}
    for case in CASES:
        study, seconds, error = run_study(binary, case)
        if error:
            checks.append(Check("study", case.name, math.nan, 1.0, f"internodes study failed: {error}"))
            continue
        lines, case_checks, case_figures = case_section(case, study, seconds, out_dir)
        text += lines
        checks += case_checks
        figures += case_figures
        data[case.name] = {"seconds": seconds, "study": study}
    return SuiteResult(title=title, checks=checks, figures=figures, text="\n".join(text), data=data)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--binary", type=Path, default=REPO / "target/release/internodes")
    parser.add_argument("--out", type=Path, default=VALIDATION / "report" / "refinement_study")
    args = parser.parse_args()
    start = time.perf_counter()
    result = run_suite(args.binary, False, args.out)
    print(result.text)
    for c in result.checks:
        print(f"{'MET ' if c.passed else 'MISS'}  {c.check}: {c.case}: {c.figure:.3g} (<= {c.tolerance:g})  {c.note}")
    print(f"\n{time.perf_counter() - start:.0f} s")
    return 0 if all(math.isfinite(c.figure) for c in result.checks) else 1


if __name__ == "__main__":
    sys.exit(main())
