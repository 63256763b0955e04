"""Accuracy of the 12 -> 6 mm lens change under pixel noise, and how far a run reported
``converged`` can be from the goal.

For each noise level (Gaussian, pixels, on every current image) the built-in ``noise-12-6``
(the lens change of sec. 5.2 on a clearly 3D object, stop rule on errors averaged over 50
images: ``||s - s*|| < 2e-3``, ``|tau_21| < 1e-3``) runs with ``--seeds`` noise seeds in one
``vsinv.run_batch``. The table gives the final translation and rotation errors (median and
largest), how many runs were reported converged, and how many of those reports are wrong:
converged farther than 5 mm or 0.5 degrees from the goal. Exit code 1 if any report is wrong.

Usage::

    python benches/noise_accuracy.py [--seeds 100] [--levels 0,0.25,0.5,1,2]
"""

from __future__ import annotations

import argparse
import copy
import sys
from typing import Any

import numpy as np

import vsinv

WRONG_MM, WRONG_DEG = 5.0, 0.5


def runs_at(base: dict[str, Any], sigma: float, seeds: int) -> dict[str, np.ndarray]:
    scenarios = []
    for seed in range(seeds):
        d = copy.deepcopy(base)
        d["noise"] = {"pixel_sigma": sigma, "seed": seed}
        scenarios.append(d)
    return vsinv.run_batch(scenarios)


def row(sigma: float, t: dict[str, np.ndarray]) -> tuple[str, int]:
    mm, deg = t["final_translation_error_mm"], t["final_rotation_error_deg"]
    converged = t["status"] == "converged"
    wrong = int((converged & ((mm > WRONG_MM) | (deg > WRONG_DEG))).sum())
    cells = [
        f"{sigma:g}",
        str(len(mm)),
        f"{np.median(mm):.3f} / {mm.max():.3f}",
        f"{np.median(deg):.4f} / {deg.max():.4f}",
        f"{int(np.median(t['iterations']))}",
        f"{int(converged.sum())}",
        str(wrong),
    ]
    return "| " + " | ".join(cells) + " |", wrong


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--levels", default="0,0.25,0.5,1,2")
    args = parser.parse_args()
    base = vsinv.load_scenario("noise-12-6").to_dict()
    print("| pixel noise (px) | runs | translation error median / max (mm) | rotation error median / max (deg) "
          "| median iterations | reported converged | of which wrong (> 5 mm or > 0.5 deg) |")
    print("|---|---|---|---|---|---|---|")
    wrong = 0
    for sigma in (float(s) for s in args.levels.split(",")):
        line, w = row(sigma, runs_at(base, sigma, args.seeds))
        print(line, flush=True)
        wrong += w
    return 1 if wrong else 0


if __name__ == "__main__":
    sys.exit(main())
