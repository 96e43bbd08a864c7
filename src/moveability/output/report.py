"""A self-contained HTML report of an analysis: spec, summary, a tool to explore the
regions by clicking poses, the planned motion and every figure.

The page embeds everything it shows (figures as data URIs, its script and style,
the analysis's cells, see :mod:`moveability.output.report_cells`), so that it
opens from disk in a browser without a server and fetches nothing.
"""

from __future__ import annotations

import base64
import html
import io
import itertools
import json
import math
import os
import re
from collections.abc import Mapping, Sequence
from importlib import resources
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import MoveabilityError
from ..types import word

if TYPE_CHECKING:
    from ..analysis.result import Analysis
    from ..mechanisms.base import Mechanism
    from .report_cells import PageCells

__all__ = ["spec_toml", "write_report"]

_TITLES = {
    "workspace": "Workspace",
    "postures": "Postures",
    "regions": "Regions",
    "joint-space": "Joint space",
    "path": "Planned motion",
    "slices": "Slices of the regions",
    "regions-3d": "Regions in 3-D",
}

_CAPTIONS = {
    "workspace": "The workspace W with the parallel-singularity loci (det A = 0) of each "
    "posture and the serial-singularity loci of each leg; grey: undecided cells.",
    "postures": "The mechanism at one pose in each of its postures.",
    "regions": "Each N-connected region W_Nj (solid: certified; pale: where it may extend, "
    "its undecided band) and an overlay of their certified parts (mixed colours where "
    "several regions hold a pose).",
    "joint-space": "The joint space Q, each joint vector coloured by the regions its "
    "configurations lie in (mixed colours where its assembly modes lie in two regions; "
    "grey: undecided; pale rose: excluded by a passive joint limit, an obstacle or a "
    "link collision), with the joint limits.",
    "path": "Snapshots of the planned motion: its first and last configurations, each "
    "posture change and the poses asked, X1, ..., Xm.",
    "slices": "Slices of the regions at four orientations (solid: certified; light: where a "
    "region may extend; grey: undecided, in no region), with the outline of W.",
    "regions-3d": "The certified part of each region in (x, y, phi): the outer faces of its cells.",
}

#: CSS size of the drawing of the explorer (pixels)
_CANVAS = (640, 600)
_WORKSPACE_COLOR = "#E4ECF5"
_UNDECIDED_COLOR = "#C8C8C8"
_LINK_COLOR = "#1A1A1A"


def _title(name: str) -> str:
    return _TITLES.get(name, name.replace("-", " ").capitalize())


def _sig(value: float, digits: int = 4) -> str:
    """A number with at most ``digits`` significant digits."""
    return f"{float(value):.{digits}g}"


def _pose_text(pose: Sequence[float], names: Sequence[str]) -> str:
    return f"({', '.join(names)}) = ({', '.join(_sig(v) for v in pose)})"


# ------------------------------------------------------------------ spec
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _toml_key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else json.dumps(key, ensure_ascii=False)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        v = float(value)
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(value, str):
        # a JSON string is a TOML basic string
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, Mapping):
        return (
            "{"
            + ", ".join(f"{_toml_key(str(k))} = {_toml_value(v)}" for k, v in value.items())
            + "}"
        )
    if isinstance(value, Sequence | np.ndarray):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"no TOML form for {type(value).__name__}")


def _angle(value: Any) -> Any:
    """An angle as the spec reads it: ``"pi/2"`` where it is a simple multiple of pi."""
    from ..spec import format_angle, parse_angle

    if isinstance(value, bool) or not isinstance(value, int | float):
        return value
    text = format_angle(float(value))
    # only where the text reads back as the same number
    if "pi" in text and parse_angle(text) == float(value):
        return text
    return value


def _with_angles(spec: Mapping[str, Any], mechanism: Mechanism) -> dict[str, Any]:
    """The spec with revolute joint limits, passive joint limits and the bounds of
    periodic pose angles written as multiples of pi where they are."""
    out = dict(spec)
    limits = spec.get("limits")
    if isinstance(limits, Mapping):
        revolute = {
            name
            for name, lim in zip(mechanism.joint_names, mechanism.limits, strict=True)
            if not lim.prismatic
        }
        out["limits"] = {
            joint: [_angle(v) for v in lim]
            if joint in revolute and isinstance(lim, Sequence) and not isinstance(lim, str)
            else lim
            for joint, lim in limits.items()
        }
    passive = spec.get("passive_limits")
    if isinstance(passive, Mapping):
        # passive joints are revolute
        out["passive_limits"] = {joint: [_angle(v) for v in lim] for joint, lim in passive.items()}
    legs = spec.get("legs")
    if isinstance(legs, Sequence) and not isinstance(legs, str):
        # a user-defined leg's passive angles: { angle = "...", limits = [lo, hi] }
        out["legs"] = [_with_passive_angles(leg) for leg in legs]
    bounds = spec.get("bounds")
    periodic = set(spec.get("periodic") or ())
    if isinstance(bounds, Mapping) and periodic:
        out["bounds"] = {
            name: [_angle(v) for v in pair] if name in periodic else pair
            for name, pair in bounds.items()
        }
    return out


def _with_passive_angles(leg: Any) -> Any:
    """A user-defined leg's table with its passive limits as multiples of pi
    where they are."""
    passive = leg.get("passive") if isinstance(leg, Mapping) else None
    if not isinstance(passive, Mapping):
        return leg
    angles = {}
    for name, entry in passive.items():
        limits = entry.get("limits") if isinstance(entry, Mapping) else None
        if isinstance(limits, Sequence) and not isinstance(limits, str):
            entry = {**entry, "limits": [_angle(v) for v in limits]}
        angles[name] = entry
    return {**leg, "passive": angles}


def spec_toml(mechanism: Mechanism) -> str:
    """The mechanism's spec as a TOML file that :func:`moveability.load_spec` reads.

    Angles of revolute joints are written as multiples of pi where they are
    (``"pi/2"``); arrays stay on one line.

    Examples
    --------
    >>> from moveability.mechanisms import FiveBar
    >>> print(spec_toml(FiveBar(7, 8, 5, 8, 5)))
    mechanism = "five-bar"
    <BLANKLINE>
    [parameters]
    L0 = 7.0
    L1 = 8.0
    L2 = 5.0
    L3 = 8.0
    L4 = 5.0
    <BLANKLINE>
    [limits]
    theta1 = [0.0, "pi"]
    theta2 = [0.0, "pi"]
    """
    spec = _with_angles(mechanism.to_spec(), mechanism)
    plain = {k: v for k, v in spec.items() if not _is_table(v) and not _is_table_array(v)}
    lines = [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in plain.items()]
    for key, value in spec.items():
        if _is_table(value):
            lines += ["", f"[{_toml_key(key)}]"]
            lines += [f"{_toml_key(str(k))} = {_toml_value(v)}" for k, v in value.items()]
        elif _is_table_array(value):
            for entry in value:
                lines += ["", f"[[{_toml_key(key)}]]"]
                lines += [f"{_toml_key(str(k))} = {_toml_value(v)}" for k, v in entry.items()]
    return "\n".join(lines)


def _is_table(value: Any) -> bool:
    return isinstance(value, Mapping)


def _is_table_array(value: Any) -> bool:
    return (
        isinstance(value, Sequence)
        and not isinstance(value, str)
        and len(value) > 0
        and all(isinstance(v, Mapping) for v in value)
    )


# --------------------------------------------------------------- figures
def _png(fig: Any) -> str:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=90, bbox_inches="tight")
    import matplotlib.pyplot as plt

    plt.close(fig)
    return base64.b64encode(buffer.getvalue()).decode("ascii")


def _figure_html(name: str, payload: str) -> str:
    if payload.startswith("unavailable"):
        body = f"<p>{html.escape(payload)}</p>"
    else:
        alt = f"{_title(name)} figure"
        body = f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{payload}">'
    return (
        f'<figure id="{name}"><h3>{html.escape(_title(name))}</h3>{body}'
        f"<figcaption>{html.escape(_CAPTIONS.get(name, ''))}</figcaption></figure>"
    )


# -------------------------------------------------------------- analysis
def _widths_text(widths: Any, names: Sequence[str]) -> str:
    times = " \u00d7 "
    return times.join(_sig(v) for v in widths) + f" ({times.join(names)})"


def _analysis_html(result: Analysis) -> str:
    from ..analysis.result import count_text
    from ..hypertree.status import BOUNDARY

    data = result.to_dict()
    names = list(result.mechanism.pose_names)
    measure = result.measure_name
    tree = result.tree
    widths = tree.cell_widths()
    at_precision = result.cell_size
    smallest = widths[np.argmax(tree.levels)] if len(tree) else at_precision
    undecided = tree.status == BOUNDARY
    w = data["workspace"][measure]
    und = data["undecided"]
    facts = [
        (
            "Precision",
            f"{', '.join(_sig(v) for v in np.atleast_1d(result.precision))} "
            "(cells are split until at most this wide where undecided)",
        ),
        (
            "Cells at the precision",
            _widths_text(at_precision, names) + ": undecided cells are at most this size",
        ),
    ]
    if not np.allclose(smallest, at_precision):
        facts.append(
            (
                "Smallest cells",
                _widths_text(smallest, names)
                + " (cells refined below the precision to settle the count of regions)",
            )
        )
    facts += [
        ("Cells of the analysis", f"{len(tree)} leaves, {int(undecided.sum())} of them undecided"),
        ("Regions", count_text(*result.count)),
        ("W N-connected", f"<strong>{word(data['n_connected'])}</strong>"),
        (f"Workspace {measure}", f"in [{w[0]:.4f}, {w[1]:.4f}]"),
        (
            "Undecided",
            f"{und[f'boundary_{measure}']:.4f} of {measure} in undecided cells; "
            f"{und['components']} possible region(s) without a certified part; "
            f"{und['detached']} certified part(s) of unknown region",
        ),
    ]
    items = "\n".join(
        f"<dt>{html.escape(k)}</dt><dd>{v if k == 'W N-connected' else html.escape(v)}</dd>"
        for k, v in facts
    )
    rows = "\n".join(
        f"<tr><td>{r['id']}</td><td>{'&gt;' if r['sign'] > 0 else '&lt;'} 0</td>"
        f"<td>[{r[measure][0]:.4f}, {r[measure][1]:.4f}]</td>"
        f"<td>{word(r['equals_workspace'])}</td>"
        f"<td>{html.escape(', '.join(r['postures']))}</td></tr>"
        for r in data["regions"]
    )
    return f"""<dl class="facts">
{items}
</dl>
<table class="regions"><tr><th>Region</th><th>det A</th><th>{measure} of W_Nj [inner, outer]</th>
<th>Equals W</th><th>Postures</th></tr>
{rows}
</table>"""


# ---------------------------------------------------------------- motion
def _motion_html(
    result: Analysis, motion: Mapping[str, Any] | None, no_motion: str
) -> tuple[str, list[list[float]]]:
    """The planned motion in words, and its asked poses (for the explorer)."""
    names = list(result.mechanism.pose_names)
    if motion is None or not motion.get("path"):
        return f"<p>No motion: {html.escape(no_motion)}.</p>", []
    path = motion["path"]
    start, end = path[0]["pose"], path[-1]["pose"]
    asked: list[list[float]] = []
    given = motion.get("waypoints")
    if given is not None:
        for w in given:
            if isinstance(w, int | np.integer) and 0 <= int(w) < len(path):
                asked.append([float(v) for v in path[int(w)]["pose"]])
            elif isinstance(w, Mapping) and "pose" in w:
                asked.append([float(v) for v in w["pose"]])
            elif isinstance(w, Sequence):
                asked.append([float(v) for v in w])
    if not asked:
        asked = [[float(v) for v in start], [float(v) for v in end]]
    changes = sum(1 for a, b in itertools.pairwise(path) if a["posture"] != b["posture"])
    facts = [
        ("Region", str(motion.get("region", "?"))),
        ("Start", _pose_text(start, names)),
        ("End", _pose_text(end, names)),
    ]
    if len(asked) > 2:
        facts.append(("Through", "; ".join(_pose_text(p, names) for p in asked[1:-1])))
    length = motion.get("length")
    if isinstance(length, Mapping):
        parts = []
        for space, what in (("pose", "in pose coordinates"), ("joints", "in joint coordinates")):
            value = length.get(space)
            if isinstance(value, Mapping) and "after" in value:
                text = f"{_sig(value['after'])} {what}"
                if "before" in value and value["before"] != value["after"]:
                    text += f" (before smoothing {_sig(value['before'])})"
                parts.append(text)
            elif isinstance(value, int | float):
                parts.append(f"{_sig(value)} {what}")
        if parts:
            facts.append(("Length", "; ".join(parts)))
    elif isinstance(length, int | float):
        facts.append(("Length", _sig(length)))
    postures = list(dict.fromkeys(c["posture"] for c in path))
    facts.append(
        (
            "Configurations",
            f"{len(path)}, posture(s) {', '.join(postures)}, {changes} posture change(s)",
        )
    )
    items = "\n".join(f"<dt>{html.escape(k)}</dt><dd>{html.escape(v)}</dd>" for k, v in facts)
    return f'<dl class="facts">\n{items}\n</dl>', asked


# -------------------------------------------------------------- explorer
def _legs(mechanism: Mechanism) -> tuple[list[dict[str, Any]], bool]:
    """How the page draws each leg (the JavaScript twin of the legs' ``links``),
    and whether the legs end at a platform drawn as a polygon."""
    from ..mechanisms.biglide import SliderLeg
    from ..mechanisms.rr_leg import RRLeg
    from ..mechanisms.three_rpr import RPRLeg

    out: list[dict[str, Any]] = []
    for leg, lim in zip(mechanism.legs, mechanism.limits, strict=True):
        if isinstance(leg, RRLeg):
            out.append(
                {
                    "kind": "rr",
                    "base": [float(v) for v in leg.base],
                    "proximal": float(leg.proximal),
                    "distal": float(leg.distal),
                }
            )
        elif isinstance(leg, SliderLeg):
            out.append(
                {
                    "kind": "slider",
                    "length": float(leg.length),
                    "rail": [[float(lim.lo), 0.0], [float(lim.hi), 0.0]],
                }
            )
        elif isinstance(leg, RPRLeg):
            out.append(
                {
                    "kind": "rpr",
                    "base": [float(v) for v in leg.base],
                    "platform": [float(v) for v in leg.platform],
                }
            )
        else:
            out.append({"kind": "none"})
    platform = len(out) >= 3 and all(d["kind"] == "rpr" for d in out)
    return out, platform


def _view(result: Analysis, legs: list[dict[str, Any]], samples: int = 800) -> list[float]:
    """The plane box drawn: where W may be, the legs' rails, and the links of the
    valid configurations at a sample of poses certainly in W."""
    m = result.mechanism
    leaves = result.tree.leaves()
    certain, possible = result.workspace_cells()
    pts = [leaves.lo[possible][:, :2], leaves.hi[possible][:, :2]]
    pts += [np.asarray(leg["rail"]) for leg in legs if "rail" in leg]
    inside = np.flatnonzero(certain)
    if inside.size:
        pick = inside[np.linspace(0, inside.size - 1, min(samples, inside.size)).astype(int)]
        poses = 0.5 * (leaves.lo[pick] + leaves.hi[pick])
        joints = m.joint_angles(poses)
        for i, pose in enumerate(poses):
            for q in joints[i]:
                valid = np.isfinite(q).all() and all(
                    bool(lim.contains(v)) for lim, v in zip(m.limits, q, strict=True)
                )
                if not valid:
                    continue
                for leg, value in zip(m.legs, q, strict=True):
                    links = getattr(leg, "links", None)
                    if links is not None:
                        pts.append(np.asarray(links(pose, float(value)))[:, :2])
    if not any(len(p) for p in pts):
        pts = [result.tree.lo[None, :2], result.tree.hi[None, :2]]
    box = np.concatenate([p for p in pts if len(p)])
    lo, hi = box.min(axis=0), box.max(axis=0)
    pad = 0.04 * float((hi - lo).max())
    return [float(lo[0] - pad), float(lo[1] - pad), float(hi[0] + pad), float(hi[1] + pad)]


def _explore_data(result: Analysis, cells: PageCells, planned: list[list[float]]) -> dict[str, Any]:
    from .axes import PALETTE

    m = result.mechanism
    meta, blob = cells.payload()
    legs, platform = _legs(m)
    return {
        "cells": meta,
        "cells_blob": base64.b64encode(blob).decode("ascii"),
        "regions": [
            {"id": r.id, "sign": r.sign, "color": PALETTE[j % len(PALETTE)]}
            for j, r in enumerate(result.regions)
        ],
        "pose_names": list(m.pose_names),
        "joint_names": list(m.joint_names),
        "limits": [
            {"lo": float(lim.lo), "hi": float(lim.hi), "prismatic": bool(lim.prismatic)}
            for lim in m.limits
        ],
        "postures": m.postures.tolist(),
        "posture_names": [m.posture_name(i) for i in range(len(m.postures))],
        "legs": legs,
        "platform": platform,
        "wrap_lo": [float(v) for v in m.bounds[0]],
        "view": _view(result, legs),
        "canvas_width": _CANVAS[0],
        "canvas_height": _CANVAS[1],
        "colors": {"workspace": _WORKSPACE_COLOR, "undecided": _UNDECIDED_COLOR},
        "posture_colors": [_LINK_COLOR],
        "max_frames": 400,
        "planned": [[float(v) for v in p] for p in planned],
    }


def _explore_html(result: Analysis, planned: list[list[float]], max_cells: int) -> str:
    k = result.tree.ndim
    if k not in (2, 3):
        return (
            "<p>The explorer draws the regions in the plane: it needs two pose axes, or "
            f"three with the third as a slider; this mechanism has {k}.</p>"
        )
    from .report_cells import page_cells

    cells = page_cells(result, max_cells=max_cells)
    data = _explore_data(result, cells, planned)
    names = list(result.mechanism.pose_names)
    regions = result.regions
    swatches = "".join(
        f'<label class="explore-show"><input type="checkbox" checked data-region="{j}">'
        f'<span class="legend-swatch" style="background:{data["regions"][j]["color"]}"></span>'
        f"region {r.id} (det A {'&gt;' if r.sign > 0 else '&lt;'} 0)</label>"
        for j, r in enumerate(regions)
    )
    heads = f"<th>({html.escape(', '.join(names))})</th><th>in W</th>"
    heads += "".join(f"<th>region {r.id}</th>" for r in regions)
    slider = ""
    if k == 3:
        lo, hi = float(result.mechanism.bounds[0][2]), float(result.mechanism.bounds[1][2])
        step = (hi - lo) / 720
        slider = (
            f'<div class="explore-controls"><label>Slice drawn and clicked: '
            f'<input type="range" class="explore-slice" min="{lo!r}" max="{hi - step!r}" '
            f'step="{step!r}" value="{0.5 * (lo + hi)!r}"></label>'
            f'<span class="explore-slice-value"></span></div>'
        )
    merged = len(cells.tree) < cells.leaves
    note = f"The page holds {len(cells.tree)} cells: the analysis's {cells.leaves} leaves" + (
        ", sibling leaves with the same answers merged (the answers do not change)"
        if merged
        else ""
    )
    if cells.coarse:
        note += (
            f"; to keep the page small, the finest cells are also merged keeping only what all "
            f"of them certify: on {100 * cells.coarsened:.2g}% of the box the page answers "
            "unknown where the analysis's cells decide (the library's answers there are in "
            "the command line's locate and feasible)"
        )
    note += "."
    if any(leg["kind"] == "none" for leg in data["legs"]):
        note += (
            " The page draws the legs of the five-bar, the biglide and the 3-RPR; for this"
            " mechanism a motion moves the platform point alone."
        )
    if result.table.group.any() and not len(cells.folds):
        note += (
            " The page knows no way across the cells where a leg folds here: its motions"
            " keep one posture."
        )
    planned_button = (
        '<button type="button" class="explore-planned">Poses of the planned motion</button>'
        if planned
        else ""
    )
    payload = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    axes_text = (
        f"poses X1, X2, ... ({', '.join(names)})"
        if k == 2
        else f"poses X1, X2, ... ({', '.join(names)}), {names[2]} set by the slider"
    )
    return f"""<p>Click the drawing to add {axes_text}. The table says for each pose whether it
lies in W and in each region: yes, no, or unknown at this precision. The line above it says
whether one region holds a configuration of every pose, so that a motion joins them without
parallel singularity and within the joint limits (feasible: yes / no / unknown). The page
computes these answers itself from the analysis's cells, as <code>moveability locate</code>
and <code>feasible</code> do: a cell certainly in a region says yes, a cell the region cannot
meet says no, a cell of its undecided band unknown. Where a leg folds in a cell the library
also tests the pose itself and may decide where the page says unknown; the page never gives a
definite answer the library would not.</p>
<p class="note">{html.escape(note)}</p>
<div id="explore-tool" class="explore-layout">
<div class="explore-main">
<div class="explore-controls">{swatches}</div>
{slider}
<div class="explore-frame"><canvas class="explore-cells"></canvas>
<canvas class="explore-overlay" role="img"
 aria-label="The regions in the plane; click to add a pose"></canvas></div>
<p class="note"><span class="legend-swatch" style="background:{_WORKSPACE_COLOR}"></span>W (certain)
<span class="legend-swatch" style="background:{_UNDECIDED_COLOR}"></span>undecided;
each region: strong where certain, light where it may extend (its undecided band).</p>
</div>
<div class="explore-side">
<div class="explore-controls"><button type="button" class="explore-undo">Undo</button>
<button type="button" class="explore-clear">Clear</button>
<button type="button" class="explore-play">Pause</button>{planned_button}</div>
<p class="feasible-answer" data-answer="none"></p>
<table class="pose-answers"><thead><tr><th>Pose</th>{heads}</tr></thead><tbody></tbody></table>
<p class="motion-status" data-state="none"></p>
<p class="motion-frame"></p>
<p class="explore-error" hidden></p>
<noscript><p>The explorer needs JavaScript.</p></noscript>
</div>
</div>
<script type="application/json" id="explore-data">{payload}</script>"""


# ------------------------------------------------------------------ page
def _asset(name: str) -> str:
    return resources.files(__package__).joinpath(name).read_text(encoding="utf-8")


def write_report(
    result: Analysis,
    out_dir: str | os.PathLike[str],
    motion: Mapping[str, Any] | None = None,
    no_motion: str = "no motion was planned",
    spec_path: str | os.PathLike[str] | None = None,
    *,
    max_cells: int | None = None,
) -> str:
    """Write ``index.html`` into ``out_dir`` and return its path.

    Parameters
    ----------
    result : Analysis
    out_dir : path
        Created if missing; ``index.html`` in it is overwritten.
    motion : mapping, optional
        A motion from :func:`moveability.plan_motion`: its poses and length are
        given, and it is drawn in the path figure; without one, the page says why
        (``no_motion``).
    spec_path : path, optional
        The spec file analysed; the page names it (its file name only).
    max_cells : int, optional
        Cells the explorer may embed before it is coarsened (see
        :mod:`moveability.output.report_cells`).
    """
    from .plot import figure, figures_for
    from .report_cells import MAX_CELLS

    os.makedirs(out_dir, exist_ok=True)
    m = result.mechanism
    images = []
    # two pose axes: the plane figures; three: slices and a 3-D view
    for name in figures_for(result):
        if name == "path" and motion is None:
            images.append((name, f"unavailable: {no_motion}"))
            continue
        try:
            images.append((name, _png(figure(name, result, motion=motion))))
        except MoveabilityError as error:  # e.g. no certified motion to draw
            images.append((name, f"unavailable: {error}"))
    motion_text, planned = _motion_html(result, motion, no_motion)
    explore = _explore_html(result, planned, MAX_CELLS if max_cells is None else max_cells)
    # without a motion the section says why; no empty figure
    path_figure = "".join(_figure_html(n, p) for n, p in images if n == "path" and motion)
    others = [(n, p) for n, p in images if n != "path"]
    figures = "\n".join(_figure_html(n, p) for n, p in others)
    sections = [
        ("mechanism", "Mechanism", []),
        ("analysis", "Analysis", []),
        ("explore", "Explore the regions", []),
        ("motion", "Planned motion", []),
        ("figures", "Figures", [(n, _title(n)) for n, _ in others]),
    ]
    contents = "\n".join(
        f'<li><a href="#{sid}">{html.escape(title)}</a>'
        + (
            "<ol>"
            + "".join(f'<li><a href="#{n}">{html.escape(t)}</a></li>' for n, t in subs)
            + "</ol>"
            if subs
            else ""
        )
        + "</li>"
        for sid, title, subs in sections
    )
    source = (
        f"from <code>{html.escape(os.path.basename(os.fspath(spec_path)))}</code>"
        if spec_path is not None
        else "as given to the analysis"
    )
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>moveability report: {html.escape(m.name)}</title>
<style>
{_asset("report_page.css")}
</style></head>
<body>
<h1>Regions of feasible point-to-point motions: {html.escape(m.name)}</h1>
<p class="subtitle">The regions R_j of configurations free of parallel singularity within the
joint limits, their projections W_Nj on the workspace W (the N-connected regions), and the
motions they allow; every answer certified: yes, no, or unknown at the precision.</p>
<nav class="contents"><h2>Contents</h2><ol>
{contents}
</ol></nav>
<section id="mechanism"><h2>Mechanism</h2>
<p>{html.escape(m.name)}, pose ({html.escape(", ".join(m.pose_names))}), joints
({html.escape(", ".join(m.joint_names))}); specification {source}:</p>
<pre class="spec">{html.escape(spec_toml(m))}</pre>
</section>
<section id="analysis"><h2>Analysis</h2>
{_analysis_html(result)}
</section>
<section id="explore"><h2>Explore the regions</h2>
{explore}
</section>
<section id="motion"><h2>Planned motion</h2>
{motion_text}
{path_figure}
</section>
<section id="figures"><h2>Figures</h2>
{figures}
</section>
<script>
{_asset("report_page.js")}
</script>
</body></html>
"""
    path = os.path.join(os.fspath(out_dir), "index.html")
    with open(path, "w", encoding="utf-8") as handle:
        handle.write(page)
    return path
