"""The paper's analysis of the five-bar RR-RRR, certified (run by ``make demo``).

For each of the paper's joint-limit cases it prints the regions R_j, the areas
of the N-connected regions W_Nj, whether the workspace W is N-connected, and
feasibility questions with witness postures; it writes every figure and an
HTML report for each case to ``out/<case>/``. Then the same for the biglide
and the 3-RPR of ``examples/``.
"""

from __future__ import annotations

import sys
import time

import matplotlib

matplotlib.use("Agg")
from pathlib import Path

import matplotlib.pyplot as plt

from moveability import analyze, default_poses, load_spec, plan_motion
from moveability.output.plot import FIGURES, figure, figures_for
from moveability.output.report import write_report
from moveability.output.vtk import export_vtk

HERE = Path(__file__).parent
OUT = HERE.parent / "out"
PRECISION = 0.035
# two poses of W in one region; two poses of W in different regions (like the
# paper's X1 and X2); two poses near the top and bottom corners of W, where both
# legs are stretched
PAIRS_PAPER = [[[1.0, 3.0], [5.0, 3.0]], [[-4.0, -1.0], [3.5, 1.5]]]
PAIRS_FULL = [[[0.0, 8.0], [6.0, -7.0]], [[3.5, 12.4], [3.5, -12.4]]]
CASES = [
    ("0 <= theta1, theta2 <= pi", HERE / "five-bar-paper.toml", PAIRS_PAPER),
    ("-pi <= theta1, theta2 <= pi", HERE / "five-bar-full-turn.toml", PAIRS_FULL),
    ("theta1, theta2 unlimited", HERE / "five-bar-unlimited.toml", PAIRS_FULL),
]


def main() -> None:
    for title, path, pairs in CASES:
        print(f"== five-bar, {title}  ({path.name}, precision {PRECISION})")
        start = time.perf_counter()
        result = analyze(load_spec(path), precision=PRECISION)
        seconds = time.perf_counter() - start
        print(result.summary())
        print(f"computed in {seconds:.2f} s")
        for points in pairs:
            answer = result.feasible(points)
            verdict = {True: "feasible", False: "infeasible", None: "unknown"}[answer["feasible"]]
            print(f"  moving through {points}: {verdict}", end="")
            if answer["feasible"]:
                postures = ", ".join(f"({q[0]:.3f}, {q[1]:.3f})" for q in answer["postures"])
                print(f" in region {answer['region']}, postures (t1, t2): {postures}")
            else:
                print()
        folder = OUT / path.stem
        folder.mkdir(parents=True, exist_ok=True)
        motion = plan_motion(result, default_poses(result))
        for name in FIGURES:
            fig = figure(name, result, motion=motion)
            fig.savefig(folder / f"{name}.png", dpi=100, bbox_inches="tight")
            plt.close(fig)
        print(f"  figures and report: {write_report(result, folder, motion)}")
        print()
    other_mechanisms()
    sys.stdout.flush()


def other_mechanisms() -> None:
    """The biglide and the 3-RPR of examples/, with their figures and reports."""
    for path, precision in (
        (HERE / "biglide.toml", 0.02),
        (HERE / "three-rpr.toml", (0.4, 0.4, 0.05)),
    ):
        print(f"== {path.stem}  ({path.name}, precision {precision})")
        start = time.perf_counter()
        result = analyze(load_spec(path), precision=precision)
        print(result.summary())
        print(f"computed in {time.perf_counter() - start:.2f} s")
        folder = OUT / path.stem
        folder.mkdir(parents=True, exist_ok=True)
        names = figures_for(result)
        motion = plan_motion(result, default_poses(result)) if "path" in names else None
        for name in names:
            fig = figure(name, result, motion=motion)
            fig.savefig(folder / f"{name}.png", dpi=100, bbox_inches="tight")
            plt.close(fig)
        print(f"  figures and report: {write_report(result, folder, motion)}")
        if len(result.mechanism.pose_names) == 3:
            files = export_vtk(result, folder / "vtk")
            print(f"  VTK files for ParaView: {len(files)} in {folder / 'vtk'}")
        print()


if __name__ == "__main__":
    main()
