"""Cost of the Delta robot's analysis at 1/32, 1/64 and 1/128 of each axis span.

examples/delta.toml (R = 0.2, r = 0.05, la = 0.35, lb = 0.8 m, arms in
[-pi/3, pi/2]); each precision in a fresh process: seconds of ``analyze``
(wall clock, and the process's CPU time: on a machine shared with other work
the wall clock grows with the load, the CPU time much less), leaves, peak
memory, count bounds and the workspace volume bounds. The plain pass by
default; ``--resolve`` adds the resolution (much longer). The header says
which kernels run (ahead of time, or numba's JIT where the extension is stale:
rerun ``make kernels``).
Run: ``.venv/bin/python benchmarks/bench_delta.py [--resolve] [fraction ...]``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

SPEC = Path(__file__).resolve().parents[1] / "examples" / "delta.toml"

CHILD = """
import json, resource, sys, time
import numpy as np
from moveability import analyze, from_spec, load_spec
mechanism = from_spec(load_spec(sys.argv[1]))
lo, hi = mechanism.pose_box()
eps = (np.asarray(hi) - np.asarray(lo)) / float(sys.argv[2])
analyze(mechanism, precision=tuple(8 * eps), resolve=False)  # compile the kernels, untimed
start, cpu = time.perf_counter(), time.process_time()
result = analyze(mechanism, precision=tuple(eps), resolve=sys.argv[3] == "1")
seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
print(json.dumps({
    "seconds": seconds,
    "cpu": cpu,
    "leaves": len(result.tree),
    "count": list(result.count),
    "volume": result.workspace["volume"],
    "peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
}))
"""


def main() -> None:
    args = sys.argv[1:]
    resolve = "--resolve" in args
    fractions = [int(a) for a in args if a != "--resolve"] or [32, 64, 128]
    print(f"Delta of {SPEC.name}, {'with' if resolve else 'without'} the resolution")
    env = {**os.environ, "MOVEABILITY_KERNELS_LOG": "1"}
    header = False
    for fraction in fractions:
        out = subprocess.run(
            [sys.executable, "-c", CHILD, str(SPEC), str(fraction), "1" if resolve else "0"],
            capture_output=True, text=True, check=True, env=env,
        )  # fmt: skip
        if not header:
            kernels = [line for line in out.stderr.splitlines() if "kernels:" in line]
            print(kernels[0] if kernels else "moveability: kernels: (not said)")
            print(
                f"{'fraction':>8} {'leaves':>9} {'analyze s':>9} {'cpu s':>7} {'peak MiB':>8}"
                "  count    W volume"
            )
            header = True
        row = json.loads(out.stdout.strip().splitlines()[-1])
        at_least, at_most = row["count"]
        count = str(at_least) if at_least == at_most else f"{at_least}..{at_most or '?'}"
        inner, outer = row["volume"]
        print(
            f"{'1/' + str(fraction):>8} {row['leaves']:>9,} {row['seconds']:>9.2f} "
            f"{row['cpu']:>7.2f} {row['peak_mib']:>8.0f}  {count:<7} [{inner:.3f}, {outer:.3f}]"
        )


if __name__ == "__main__":
    main()
