"""Many runs at once: the lens-change scenario with K_hat's focal length off by -50 % to
+200 %, run in Rust on all cores with `run_batch` (one table row per run). Prop. 1 says any
positive focal estimate is stable: exits non-zero unless every run converged.

    python examples/python_batch.py
"""

from __future__ import annotations

import sys

import vsinv


def main() -> int:
    base = vsinv.load_scenario("lens-12-6").to_dict()
    errors = [-0.5, -0.25, 0.0, 0.5, 1.0, 2.0]
    scenarios = []
    for e in errors:
        d = vsinv.load_scenario(base).to_dict()
        d["estimate"]["fku"] = d["estimate"]["fkv"] = 600.0 * (1 + e)
        scenarios.append(d)
    table = vsinv.sim.run_batch(scenarios)
    print("focal error | status    | iterations | final error (mm)")
    for e, status, it, err in zip(errors, table["status"], table["iterations"], table["final_translation_error"]):
        print(f"{e:+10.0%} | {status:9} | {it:10d} | {err * 1e3:.3f}")
    return 0 if all(s == "converged" for s in table["status"]) else 1


if __name__ == "__main__":
    sys.exit(main())
