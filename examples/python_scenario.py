"""A simulated run of a built-in scenario with its figures: the paper's lens change (sec. 5.2,
12 mm -> 6 mm) with the invariant law, then the same scenario edited as a dictionary to use
classic IBVS. Exits non-zero unless the invariant law converged.

    python examples/python_scenario.py [OUT_DIR]
"""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

import vsinv
from vsinv.plots import save_figures


def main(out_dir: Path) -> int:
    result = vsinv.run_scenario("lens-12-6")
    s = result.summary
    print(
        f"lens-12-6: {s['status']} after {s['iterations']} iterations, "
        f"{s['final_translation_error'] * 1e3:.3f} mm, {math.degrees(s['final_rotation_error']):.4f} deg"
    )
    written = save_figures(result, out_dir)
    print(f"{len(written)} figures in {out_dir}")

    d = vsinv.load_scenario("lens-12-6").to_dict()
    d["control"]["law"] = "ibvs"
    ibvs = vsinv.run_scenario(d, record=False).summary
    print(f"classic IBVS: {ibvs['status']}, {ibvs['final_translation_error'] * 1e3:.1f} mm from the goal")
    return 0 if s["status"] == "converged" and written else 1


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="vsinv-"))
    sys.exit(main(out))
