"""The simulator: scenarios (built-in, TOML files or dicts), single runs and their results,
batches in parallel, parameter sweeps (:mod:`vsinv.sweep` holds their parts), and the
declarations of the recorded columns and the summary's numbers."""

from ._batch import run_batch
from ._core import RunResult, Scenario, ScenarioArm, list_scenarios, load_scenario, recorded_columns, summary_fields
from ._run import run_scenario
from .sweep import Choice, LogUniform, SweepResult, Uniform, run_sweep

__all__ = [
    "Choice",
    "LogUniform",
    "RunResult",
    "Scenario",
    "ScenarioArm",
    "SweepResult",
    "Uniform",
    "list_scenarios",
    "load_scenario",
    "recorded_columns",
    "run_batch",
    "run_scenario",
    "run_sweep",
    "summary_fields",
]
