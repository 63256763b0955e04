"""Under pixel noise a run may stop short of the goal, but a run reported converged is never
far from it (benches/noise_accuracy.py makes the README's table with 100 seeds)."""

import sys
from pathlib import Path

import numpy as np

import vsinv

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
import noise_accuracy  # noqa: E402


def test_converged_reports_are_never_far_from_the_goal():
    base = vsinv.load_scenario("noise-12-6").to_dict()
    for sigma in (0.0, 0.5, 1.0, 2.0):
        table = noise_accuracy.runs_at(base, sigma, seeds=10)
        _, wrong = noise_accuracy.row(sigma, table)
        assert wrong == 0, sigma
        converged = table["status"] == "converged"
        assert np.all(table["final_translation_error_mm"][converged] < noise_accuracy.WRONG_MM)
        if sigma == 0.0:
            assert converged.all() and table["final_translation_error_mm"].max() < 1.0
