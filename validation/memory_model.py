#!/usr/bin/python3
"""A memory model per rank, measured: the heap at its peak per part on 1, 2 and 4 ranks at four
sizes of the contact benchmark's case, each part fitted as a power of the size times a share
that the ranks divide, and extrapolated to 100M DOFs on 64 and 256 ranks.

The case: ``geo/hemisphere_on_block.toml`` (the demo's sphere on a block) in one load step at
the contact benchmark's levels 0.25, 1.25, 2.02 and 2.56 (31k, 217k, 1.02M and 3.06M DOFs;
meshed once each by gmsh into ``validation/build/memory_model``, the last in about 4.5 minutes). Each run goes through
``memory_breakdown.breakdown`` (heaptrack, the bytes each part holds when a rank's heap is at
its peak). For each part, with ``n`` the DOFs and ``N`` the ranks, the model of a distributed
run is

    MB per rank = c n^p (s / N + 1 - s),

``c`` and ``p`` from the 2-rank runs at 217k and 1M (``FIT_SIZES``), the share ``s`` that the
ranks divide from the 2- and 4-rank runs at 1M (a rank's mean over the ranks). Not at 3M, though
the issue asked for that size: there each rank's peak can fall in another phase (at cd77ade's and
f3d1d4d's 3M on 2 ranks one rank peaked in the contact loop and the other inside GAMG's set-up of
the second body, 20 MB apart, so the mean held half a GMRES basis and a hierarchy with one
product's intermediate data), and a fit on it reads the parts of a phase as parts no rank divides;
3M tests the extrapolation instead, three times beyond the sizes fitted. The report counts the
ranks whose peak holds the GMRES basis (in the contact loop). The other
distributed runs are not used by the fit: they test it (printed against the model). The fit reads each part at each rank's peak, and the moment of that peak moves
between runs: since the ranks keep only their rows of the Krylov vectors and of the coupling
blocks, the 4-rank run at 217k peaked where its GMRES basis held 0.4 MB (23 MB on 2 ranks), so
the 2-rank runs took its place in the fit. (Rank 0 also peaked at 1M in the post-processing,
while it held the strain and stress fields and a gathered copy of the grid to write them; since
the output is written a chunk at a time, every rank peaks in the contact loop: the report marks
whether the GMRES basis is live at a run's peak.) One process is another program (it keeps the whole stiffness for the body
solves, and several threads run dense products), so the serial runs are shown, not fitted. The
contact surface grows like ``n^(2/3)`` under uniform refinement and the half-space blocks like
its square: the exponents are measured, not assumed (but the one of ``FIXED_EXPONENTS``, whose
method changes between the fitted sizes), and two points give them to about 0.1 only (the GMRES
basis follows its iteration count). 4 ranks on a 2-core machine are
oversubscribed: fine for memory, not for time.

The heap counts what was allocated, not what was written: faer's dense products reserve a
thread-local buffer of twice the reported L3 cache that is mostly never written
(``memory_breakdown.PARTS``), a part of its own here, shown but left out of the test and the
extrapolation (the resident memory, ``rank_peak_memory_mb``, is shown beside the heap).

The measurements go to ``validation/memory_model.json``; ``--refit`` prints the model from that
file and runs nothing.

Usage:  /usr/bin/python3 validation/memory_model.py [--binary PATH] [--out FILE.md] [--refit]
                                                     [--only 3M:2,3M:4]
Takes about 55 minutes on this 2-core machine (half of them the 3M runs under heaptrack and their mesh).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import subprocess
import sys
import tomllib
from pathlib import Path

from memory_breakdown import PARTS, breakdown
from suite import mesh_geo

REPO = Path(__file__).resolve().parent.parent
BUILD = REPO / "validation" / "build" / "memory_model"
CASE = REPO / "geo" / "hemisphere_on_block.toml"
MEASUREMENTS = REPO / "validation" / "memory_model.json"
# (name, refinement level of geo/hemisphere_on_block.geo), as in contact_benchmark.SIZES.
SIZES = (("31k", 0.25), ("217k", 1.25), ("1M", 2.02), ("3M", 2.56))
RANKS = (1, 2, 4)
# Where the model is extrapolated to: (DOFs, ranks).
TARGETS = ((100e6, 64), (100e6, 256))
BUFFER = PARTS[0][0]  # faer's dense-product buffer: reserved, mostly never written


def case_file(level: float) -> Path:
    """The demo case in one load step on its mesh at ``level`` (meshed once: ``suite.mesh_geo``
    caches it)."""
    case = tomllib.loads(CASE.read_text())
    msh = mesh_geo(Path(case["mesh"]).stem, 3, {**case["geo_parameters"], "level": level},
                   BUILD / f"hemisphere_on_block_level{level}.msh")
    text = CASE.read_text()
    text = re.sub(r'^mesh = .*$', f'mesh = "{msh.name}"', text, flags=re.M)
    text = re.sub(r'^geo_parameters = .*\n', "", text, flags=re.M)
    text = re.sub(r'^load_steps = .*$', "load_steps = [1.0]", text, flags=re.M)
    path = BUILD / f"case_level{level}.toml"
    path.write_text(text)
    return path




# Parts whose growth is known and which the fitted sizes (FIT_SIZES) do not show: the half-space
# preconditioner changes method between them (assembled and LU-factored on at most 1,000
# multipliers, which the 217k run has in its last iterations; the two-level inverse at 1M, which
# keeps per multiplier its fine level's 20 nodes and the coarse columns of its near clusters, a
# number that does not grow with the zone: the contact zone's growth, n^(2/3). Its coarse factor,
# (3m/128)^2, grows like n^(4/3) but is 18 MB at 100M, which this exponent leaves out.) Its
# replicated share is 0 (every rank holds all of it); c from the largest size.
FIXED_EXPONENTS = {"half-space preconditioner (S~^-1)": 2 / 3}


# The rank count of the runs ``c`` and ``p`` are fitted on (the script's doc says why 2).
FIT_RANKS = 2
# The sizes the model is fitted on (the script's doc says why not 3M): ``c`` and ``p`` from
# their ``FIT_RANKS``-rank runs, the share ``s`` from the 2- and 4-rank runs at the larger.
FIT_SIZES = ("217k", "1M")
# A part held only in the contact loop: a run whose peak holds none of it peaked elsewhere.
LOOP_PART = "GMRES basis and vectors"


def fit(mb: dict, parts: list[str], dofs: dict) -> dict:
    """(c, p, s) per part from the ``FIT_RANKS``-rank runs at the ``FIT_SIZES`` and the 2- and
    4-rank runs at the larger (``mb[size, ranks][part]``, MB)."""
    (small, large) = FIT_SIZES
    model = {}
    for part in parts:
        b_small, b_large = mb[small, FIT_RANKS].get(part, 0.0), mb[large, FIT_RANKS].get(part, 0.0)
        if part in FIXED_EXPONENTS and b_large > 0:
            p = FIXED_EXPONENTS[part]
            model[part] = (b_large / dofs[large] ** p, p, 0.0)
            continue
        if b_small <= 0 or b_large <= 0:
            model[part] = (b_large, 0.0, 0.0)
            continue
        p = math.log(b_large / b_small) / math.log(dofs[large] / dofs[small])
        # b_N = k (s / N + 1 - s): r = b_2 / b_4 = (1 - s / 2) / (1 - 3 s / 4) gives
        # s = (r - 1) / (3 r / 4 - 1 / 2).
        b_four = mb[large, 4].get(part, 0.0)
        r = mb[large, 2].get(part, 0.0) / b_four if b_four > 0 else 1.0
        share = min(max((r - 1) / (0.75 * r - 0.5), 0.0), 1.0)
        c = b_large / dofs[large] ** p / (share / FIT_RANKS + 1 - share)
        model[part] = (c, p, share)
    return model


def predict(model: tuple, n: float, ranks: int) -> float:
    c, p, s = model
    return c * n ** p * (s / ranks + 1 - s)


def measure(binary: Path, only: set | None = None, kept: dict | None = None) -> dict:
    """Every size on every rank count (or the runs ``only`` names, as (size, ranks), the others
    kept from ``kept``, an earlier measurement): heap per part (MB, a rank's mean), resident
    peak, and the commit of the binary of each run."""
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True,
                            text=True).stdout.strip()
    runs = []
    dofs, contact_nodes = dict((kept or {}).get("dofs", {})), dict((kept or {}).get("contact_nodes", {}))
    for name, level in SIZES:
        case = None
        for ranks in RANKS:
            if only is not None and (name, ranks) not in only:
                old = next(r for r in kept["runs"] if (r["size"], r["ranks"]) == (name, ranks))
                runs.append({"binary_commit": kept.get("binary_commit"), **old})
                continue
            # Meshed only for the sizes that run.
            case = case or case_file(level)
            print(f"{name} on {ranks} rank(s) ...", file=sys.stderr, flush=True)
            columns, summary, log = breakdown(case, ranks, binary)
            parts = {p for c in columns for p in c}
            runs.append({"size": name, "ranks": ranks,
                         "heap_mb": {p: sum(c.get(p, 0) for c in columns) / ranks / 1e6 for p in parts},
                         "rank_heap_mb": [{p: v / 1e6 for p, v in c.items()} for c in columns],
                         "resident_peak_mb_largest_rank":
                             max(summary.get("rank_peak_memory_mb") or [summary.get("peak_memory_mb")]),
                         "binary_commit": commit})
            dofs[name] = sum(body["num_dofs"] for body in summary["bodies"])
            contact_nodes[name] = sum(int(k) for k in re.findall(r"(\d+) candidate nodes", log))
    return {"case": "geo/hemisphere_on_block.toml, one load step", "dofs": dofs,
            "contact_nodes": contact_nodes, "runs": runs}


def in_the_loop(run: dict) -> str:
    """How many of a run's ranks peaked in the contact loop (their GMRES basis live), in bold
    where not all; a run measured before the ranks were recorded one by one shows whether the
    mean holds the basis (some rank did)."""
    ranks = run["ranks"]
    if "rank_heap_mb" not in run:
        return "some (mean)" if run["heap_mb"].get(LOOP_PART, 0) > 0 else "**none**"
    count = sum(1 for rank in run["rank_heap_mb"] if rank.get(LOOP_PART, 0) > 0)
    return f"{count} of {ranks}" if count == ranks else f"**{count} of {ranks}**"


def report(data: dict) -> str:
    """The tables: the measurements, the fit tested on the runs it did not use, the
    extrapolation."""
    mb = {(r["size"], r["ranks"]): r["heap_mb"] for r in data["runs"]}
    resident = {(r["size"], r["ranks"]): r["resident_peak_mb_largest_rank"] for r in data["runs"]}
    dofs, contact_nodes = data["dofs"], data["contact_nodes"]
    sizes = [name for name, _ in SIZES]
    parts = sorted({p for m in mb.values() for p in m}, key=lambda p: -mb[sizes[-1], 4].get(p, 0))
    model = fit(mb, parts, dofs)
    commits = {}
    for r in data["runs"]:
        commits.setdefault(r.get("binary_commit", data.get("binary_commit")), []).append(
            f"{r['size']} x{r['ranks']}")
    measured = "; ".join(f"commit {c}: {', '.join(runs)}" for c, runs in commits.items())
    lines = ["# Memory per rank, measured and extrapolated (`validation/memory_model.py`)", "",
             f"Measured with the binary of {measured} ({data['case']}); "
             "the model and why in the script's doc.", "",
             "## Heap per rank at its peak (MB, a rank's mean) and the fitted model", "",
             "| part | " + " | ".join(f"{s} x{r}" for s in sizes for r in RANKS) + " | p | s |",
             "|---|" + "---:|" * (len(sizes) * len(RANKS) + 2)]
    for part in parts:
        c, p, s = model[part]
        lines.append(f"| {part} | " + " | ".join(f"{mb[x, r].get(part, 0):.0f}" for x in sizes for r in RANKS)
                     + f" | {p:.2f} | {s:.2f} |")
    lines.append("| **heap at its peak** | " + " | ".join(f"**{sum(mb[x, r].values()):.0f}**"
                                                        for x in sizes for r in RANKS) + " | | |")
    lines.append("| resident peak (largest rank) | " + " | ".join(f"{resident[x, r]:.0f}"
                                                               for x in sizes for r in RANKS) + " | | |")
    in_loop = {(r["size"], r["ranks"]): in_the_loop(r) for r in data["runs"]}
    lines.append("| ranks whose peak is in the contact loop (its GMRES basis live) | "
                 + " | ".join(in_loop[x, r] for x in sizes for r in RANKS) + " | | |")
    lines += ["", "DOFs: " + ", ".join(f"{s} {dofs[s]:,}" for s in sizes)
              + "; contact candidate nodes (both surfaces): "
              + ", ".join(f"{s} {contact_nodes[s]:,}" for s in sizes) + ".", ""]
    lines += ["## The fit tested on the distributed runs it did not use (heap without the buffer)", "",
              "| run | measured MB | model MB | model / measured |", "|---|---:|---:|---:|"]
    fitted = {(FIT_SIZES[0], FIT_RANKS), (FIT_SIZES[1], FIT_RANKS), (FIT_SIZES[1], 4)}
    for x, r in ((x, r) for x in reversed(sizes) for r in RANKS[1:] if (x, r) not in fitted):
        real = sum(v for p, v in mb[x, r].items() if p != BUFFER)
        pred = sum(predict(model[p], dofs[x], r) for p in parts if p != BUFFER)
        lines.append(f"| {x} x{r} | {real:.0f} | {pred:.0f} | {pred / real:.2f} |")
    lines += ["", "## Extrapolated per rank (MB; without the buffer)", "",
              "| part | " + " | ".join(f"{sizes[-1]} x{r}" for r in RANKS[1:]) + " | "
              + " | ".join(f"{n / 1e6:.0f}M x{r}" for n, r in TARGETS) + " |",
              "|---|" + "---:|" * (len(RANKS) - 1 + len(TARGETS))]
    rows = []
    for part in parts:
        if part != BUFFER:
            row = [predict(model[part], dofs[sizes[-1]], r) for r in RANKS[1:]]
            rows.append((part, row + [predict(model[part], n, r) for n, r in TARGETS]))
    rows.sort(key=lambda item: -item[1][-1])
    for part, row in rows:
        lines.append(f"| {part} | " + " | ".join(f"{v:,.0f}" for v in row) + " |")
    totals = [sum(row[k] for _, row in rows) for k in range(len(rows[0][1]))]
    lines.append("| **total** | " + " | ".join(f"**{t:,.0f}**" for t in totals) + " |")
    return "\n".join(lines) + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--binary", type=Path, default=REPO / "target/release/internodes")
    parser.add_argument("--out", type=Path, help="also write the tables to this markdown file")
    parser.add_argument("--refit", action="store_true", help="fit the measurements file again, run nothing")
    parser.add_argument("--only", help="run only these, e.g. 3M:2,3M:4, and keep the others from the "
                        "measurements file (each run's commit is reported)")
    args = parser.parse_args()
    if args.refit:
        data = json.loads(MEASUREMENTS.read_text())
    else:
        only, kept = None, None
        if args.only:
            only = {(size, int(ranks)) for size, ranks in (item.split(":") for item in args.only.split(","))}
            kept = json.loads(MEASUREMENTS.read_text())
        data = measure(args.binary, only, kept)
        MEASUREMENTS.write_text(json.dumps(data, indent=1) + "\n")
    text = report(data)
    print(text)
    if args.out:
        args.out.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
