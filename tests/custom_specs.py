"""User-defined specs of the built-in mechanisms, for the tests that compare them."""

from __future__ import annotations

_COS = ("1", "(-1/2)", "(-1/2)")
_SIN = ("0", "(sqrt(3)/2)", "(-sqrt(3)/2)")


def five_bar_spec(lengths=(7.0, 8.0, 5.0, 8.0, 5.0), limits=(0.0, "pi")) -> dict:
    L0, L1, L2, L3, L4 = lengths
    reach = max(L1 + L2, L3 + L4)
    return {
        "mechanism": "custom",
        "pose": ["x", "y"],
        "joints": ["t1", "t2"],
        "parameters": dict(zip(("L0", "L1", "L2", "L3", "L4"), lengths, strict=True)),
        "legs": [
            {"joint": "t1", "constraint": "(x - L1*cos(t1))**2 + (y - L1*sin(t1))**2 - L2**2"},
            {
                "joint": "t2",
                "constraint": "(x - L0 - L3*cos(t2))**2 + (y - L3*sin(t2))**2 - L4**2",
            },
        ],
        "limits": {"t1": list(limits), "t2": list(limits)},
        "bounds": {"x": [-reach - 1.0, L0 + reach + 2.0], "y": [-reach - 1.0, reach + 1.0]},
    }


def custom_delta_spec(design, limits, bounds) -> dict:
    """The Delta of ``design`` and ``limits`` as a custom spec over ``bounds``."""
    R, r, la, lb = design
    legs = []
    for i in range(3):
        t, c, s = f"t{i + 1}", _COS[i], _SIN[i]
        h = f"(r - (R + la*cos({t})))"
        legs.append(
            {
                "joint": t,
                "constraint": f"(x + {c}*{h})**2 + (y + {s}*{h})**2 + (z + la*sin({t}))**2 - lb**2",
            }
        )
    lo, hi = bounds
    return {
        "mechanism": "custom",
        "pose": ["x", "y", "z"],
        "joints": ["t1", "t2", "t3"],
        "parameters": {"R": R, "r": r, "la": la, "lb": lb},
        "legs": legs,
        "limits": {f"t{i + 1}": [float(a), float(b)] for i, (a, b) in enumerate(limits)},
        "bounds": {n: [float(lo[k]), float(hi[k])] for k, n in enumerate("xyz")},
    }
