"""Draw the figures of the README and of docs/ into docs/figures/.

Run from the repository: ``.venv/bin/python docs/make_figures.py``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from moveability import analyze, default_poses, load_spec, plan_motion
from moveability.output.plot import figure

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
OUT = ROOT / "docs" / "figures"


def save(fig, name: str) -> None:
    fig.savefig(OUT / name, dpi=100, bbox_inches="tight")
    print(f"wrote docs/figures/{name}")


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    paper = analyze(load_spec(EXAMPLES / "five-bar-paper.toml"), precision=0.03)
    save(figure("workspace", paper), "five-bar-paper-workspace.png")
    save(figure("postures", paper, pose=[3.5, 6.0]), "five-bar-paper-postures.png")
    save(figure("regions", paper), "five-bar-paper-regions.png")
    save(figure("joint-space", paper), "joint-space.png")
    save(figure("path", paper, motion=plan_motion(paper, default_poses(paper))), "path.png")
    full = analyze(load_spec(EXAMPLES / "five-bar-full-turn.toml"), precision=0.03)
    save(figure("regions", full), "five-bar-full-turn-regions.png")
    rpr = analyze(load_spec(EXAMPLES / "three-rpr.toml"), precision=(0.4, 0.4, 0.1))
    save(figure("slices", rpr, phis=[-0.7853981633974483, 0.7853981633974483]),
         "three-rpr-slices.png")  # fmt: skip
    delta = analyze(load_spec(EXAMPLES / "delta.toml"), precision=0.03, resolve=False)
    save(figure("slices", delta), "delta-slices.png")


if __name__ == "__main__":
    sys.exit(main())
