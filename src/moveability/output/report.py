"""A self-contained HTML report of an analysis: spec, summary, every figure.

The page embeds its figures as data URIs, so it opens from disk in a browser
without a server.
"""

from __future__ import annotations

import base64
import html
import io
import json
import os
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from ..errors import MoveabilityError
from ..types import word

if TYPE_CHECKING:
    from ..analysis.result import Analysis

__all__ = ["write_report"]

_CAPTIONS = {
    "workspace": "The workspace W with the parallel-singularity loci (det A = 0) of each "
    "posture and the serial-singularity loci of each leg; grey: undecided cells.",
    "postures": "The mechanism at one pose in each of its postures.",
    "regions": "Each N-connected region W_Nj (dark: certified; light: undecided band) and "
    "an overlay of all of them.",
    "joint-space": "The joint space Q: parallel-singularity curves and the traces of the "
    "regions' certified configurations.",
    "path": "A planned motion inside one region, as snapshots; posture changes are marked.",
    "slices": "Slices of the regions at four orientations (solid: certified; light: where a "
    "region may extend; grey: undecided, in no region), with the outline of W.",
    "regions-3d": "The certified part of each region in (x, y, phi): the outer faces of its "
    "cells.",
}


def _png(fig: Any) -> str:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=90, bbox_inches="tight")
    import matplotlib.pyplot as plt

    plt.close(fig)
    return base64.b64encode(buffer.getvalue()).decode("ascii")


def write_report(
    result: Analysis,
    out_dir: str | os.PathLike[str],
    motion: Mapping[str, Any] | None = None,
    no_motion: str = "no motion was planned",
) -> str:
    """Write ``index.html`` into ``out_dir`` and return its path.

    ``motion`` (from :func:`moveability.plan_motion`) is drawn in the path
    figure; without one, the page says why (``no_motion``).
    """
    from .plot import figure, figures_for

    os.makedirs(out_dir, exist_ok=True)
    data = result.to_dict()
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
    measure = result.measure_name
    rows = "\n".join(
        f"<tr><td>{r['id']}</td><td>{'&gt;' if r['sign'] > 0 else '&lt;'} 0</td>"
        f"<td>[{r[measure][0]:.4f}, {r[measure][1]:.4f}]</td>"
        f"<td>{word(r['equals_workspace'])}</td><td>{', '.join(r['postures'])}</td></tr>"
        for r in data["regions"]
    )
    w = data["workspace"][measure]
    und = data["undecided"]
    figures = []
    for name, payload in images:
        if payload.startswith("unavailable"):
            body = f"<p>{html.escape(payload)}</p>"
        else:
            body = f'<img alt="{name} figure" src="data:image/png;base64,{payload}">'
        figures.append(
            f'<figure id="{name}"><h3>{name}</h3>{body}'
            f"<figcaption>{html.escape(_CAPTIONS[name])}</figcaption></figure>"
        )
    spec = json.dumps(result.mechanism.to_spec(), indent=2)
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>moveability report: {html.escape(result.mechanism.name)}</title>
<style>
body {{ font-family: sans-serif; max-width: 1100px; margin: 2em auto; color: #222; }}
table {{ border-collapse: collapse; }} td, th {{ border: 1px solid #999; padding: 4px 8px; }}
img {{ max-width: 100%; }} figure {{ margin: 2em 0; }} pre {{ background: #f4f4f4; padding: 1em; }}
</style></head>
<body>
<h1>Regions of feasible point-to-point motions</h1>
<h2>Mechanism</h2>
<pre>{html.escape(spec)}</pre>
<p>Precision: {result.precision_text} (undecided cells are at most this wide);
{data["leaves"]} cells.</p>
<h2>Summary</h2>
<p>Workspace {measure} in [{w[0]:.4f}, {w[1]:.4f}].
W is N-connected: <strong>{word(data["n_connected"])}</strong>.</p>
<table><tr><th>region</th><th>det A</th><th>{measure} of W_Nj [inner, outer]</th>
<th>equals W</th><th>postures</th></tr>
{rows}
</table>
<p>Undecided at this precision: {und[f"boundary_{measure}"]:.4f} of {measure} in undecided
cells;
{und["components"]} possible region(s) without a certified part;
{und["detached"]} certified part(s) of unknown region.</p>
<h2>Figures</h2>
{"".join(figures)}
<script>
window.addEventListener("load", function () {{
  for (const img of document.images) {{
    img.setAttribute("data-natural-width", String(img.naturalWidth));
  }}
}});
</script>
</body></html>
"""
    path = os.path.join(os.fspath(out_dir), "index.html")
    with open(path, "w", encoding="utf-8") as handle:
        handle.write(page)
    return path
