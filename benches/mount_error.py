"""How the invariant law and IBVS tolerate a hand-eye error: the camera mount the controller
believes against the true one (issue 20, item 3; scenario key ``robot.mount_error``).

How to run (from the repository root, with the package installed)::

    python benches/mount_error.py                    # about a minute
    python benches/mount_error.py --scenario arm-panda-12-6

The built-in arm scenario (default ``arm-ur5-12-6``: the camera on a UR5's flange, 290 mm and
80 degrees from the goal) is run with the reference image taken by the servo lens (6 mm;
``--lens-change`` keeps the scenario's 12 mm reference, which IBVS cannot reach whatever the
mount) and the scenario's slightly wrong K_hat, and with ``robot.mount_error``: the controller maps camera twists to joint velocities through
``camera_mount * mount_error`` while the camera moves with ``camera_mount``. Rotation errors
are about the axis (1, 1, 1)/sqrt(3) of the camera frame, translation errors along
(1, -1, 1)/sqrt(3); each row is one run per law (``control.law = "invariant"`` and
``"ibvs"``, the scenario's other keys unchanged). Columns: the verdict, the iterations, the
final translation (mm) and rotation (deg) errors from the reference pose, and the largest
distance of the camera centre from the straight line (mm).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

import vsinv

ROTATIONS_DEG = [0.0, 1.0, 2.0, 5.0, 10.0, 20.0, 30.0, 40.0, 45.0, 60.0]
TRANSLATIONS_MM = [0.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0]
ROTATION_AXIS = np.ones(3) / np.sqrt(3)
TRANSLATION_AXIS = np.array([1.0, -1.0, 1.0]) / np.sqrt(3)


def run(base: dict, law: str, rotation_deg: float, translation_mm: float) -> dict:
    d = {k: (dict(v) if isinstance(v, dict) else v) for k, v in base.items()}
    d["control"]["law"] = law
    d["robot"]["mount_error"] = {
        "position": list(TRANSLATION_AXIS * translation_mm / 1000),
        "rotation_deg": list(ROTATION_AXIS * rotation_deg),
    }
    return vsinv.run_scenario(d).summary


def row(label: str, base: dict, rotation_deg: float, translation_mm: float) -> str:
    cells = [label]
    for law in ("invariant", "ibvs"):
        s = run(base, law, rotation_deg, translation_mm)
        cells += [s["status"], str(s["iterations"]), f"{s['final_translation_error'] * 1000:.3f}",
                  f"{np.degrees(s['final_rotation_error']):.4f}", f"{s['max_line_deviation'] * 1000:.1f}"]
    return "| " + " | ".join(cells) + " |"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenario", default="arm-ur5-12-6")
    parser.add_argument("--lens-change", action="store_true", help="keep the scenario's reference lens")
    parser.add_argument("--quick", action="store_true", help="one rotation and one translation (make bench-quick)")
    args = parser.parse_args()
    rotations, translations = (ROTATIONS_DEG[:2], TRANSLATIONS_MM[:2]) if args.quick else (ROTATIONS_DEG, TRANSLATIONS_MM)
    base = vsinv.load_scenario(args.scenario).to_dict()
    if not args.lens_change:
        base["reference_camera"] = dict(base["camera"])
    lenses = "the scenario's lenses" if args.lens_change else "reference image by the servo lens"
    print(f"{args.scenario} ({lenses}): mount error of the controller against the true mount\n")
    head = "verdict | iterations | final mm | final deg | line mm"
    print(f"| mount error | invariant: {head} | IBVS: {head} |")
    print("|---|" + "---|" * 10)
    for r in rotations:
        print(row(f"{r:g} deg", base, r, 0.0))
    for t in translations[1:]:
        print(row(f"{t:g} mm", base, 0.0, t))
    print(row("10 deg + 20 mm", base, 10.0, 20.0))
    return 0


if __name__ == "__main__":
    sys.exit(main())
