"""Parameter sweeps: many closed-loop runs of one scenario with some keys varied.

>>> from vsinv.sweep import run_sweep, Uniform
>>> res = run_sweep("lens-12-6", {"focal_error": np.linspace(-0.6, 2.0, 27)}, repeats=1)
>>> res.summary_by("focal_error")["convergence_rate"]
>>> res = run_sweep("noise-12-6", {"noise.pixel_sigma": [0.0, 0.5, 1.0]}, repeats=20)
>>> res = run_sweep("lens-12-6", {"focal_error": [0.0, 0.5], "roll_deg": Uniform(-120, 120)}, draws=50)
>>> res.write("sweep.parquet")                 # CSV when pyarrow is missing

**What is varied.** ``vary`` maps a key to either a sequence of values (a grid axis; the grid
is the Cartesian product of the axes, the last key varying fastest) or a distribution
(:class:`Uniform`, :class:`LogUniform`, :class:`Choice`) sampled ``draws`` times with
``numpy.random.default_rng(seed)``; every draw is combined with every grid point. A scalar is
a one-value axis. Every point is run ``repeats`` times with different noise seeds.

**Keys.** Any dotted scenario key (docs/reference/scenario-files.md): ``"noise.pixel_sigma"``,
``"control.gain"``, ``"estimate.skew_deg"``, ``"stop.max_iterations"``, ``"start.position.2"``
(an integer segment indexes a list), ``"vision.blur_sigma"``, ``"robot.damping"``. The
scenario schema decides which keys exist: each key is applied to the base scenario and the
result parsed, so an unknown key is refused with the schema's own message. A ``camera`` or ``estimate`` section the base does not
have is filled with its default first (camera = reference camera, estimate = the servo camera
at t = 0), other missing sections are created empty. Derived keys:

- ``"lens_ratio"`` r: the servo camera's focal terms become the reference camera's times r
  (fku and fkv; a zoom schedule is scaled by the same factor). If the base has an estimate,
  its focal terms are scaled by the same factor as the servo camera's (K_hat keeps its
  relative error); without one K_hat keeps following the camera.
- ``"focal_error"`` e: K_hat's focal terms are the servo camera's at t = 0 times (1 + e):
  ``estimate.fku = camera.fku * (1 + e)``, same for fkv; K_hat's other fields are the base
  estimate's, or the camera's when the base has no estimate. e <= -1 gives an invalid K_hat.
- ``"principal_point_error"`` d: d pixels added to K_hat's u0 and v0 (K_hat = the camera
  when the base has no estimate).
- ``"roll_deg"`` a: an extra rotation about the optical axis at the start:
  ``R' = R Rz(a)`` with R the start rotation, written back as theta-u degrees.

**Arms.** ``start.*`` and ``roll_deg`` move the camera's start pose, which an arm scenario
has when it is placed by that pose (``[start]``; the joints follow by inverse kinematics,
from ``robot.ik_seed`` when given); one placed by ``robot.joints`` is refused, naming the
key. A varied start the arm cannot reach is refused as any invalid value is.

Dotted keys are applied first (in the order given), then the derived keys in the order above,
then the noise seed.

**Noise seeds.** ``noise.seed`` of run (point p, repetition k) is a 63-bit hash of
``(seed, p, k)`` (column ``"seed"``), unless ``"noise.seed"`` is itself varied.

**Errors.** Unknown or malformed keys and values that make an invalid scenario (checked for
every grid value and for each distribution's bounds) raise :class:`vsinv.InvalidInput` naming
the key before anything runs.

**Execution.** The runs' scenarios are built and run in Rust (``vsinv._core.run_sweep_runs``,
``src/sim/sweep/``): the base scenario is read once, each run's keys are applied to a copy of
it, which is parsed once on the worker that runs it (no JSON text per run). The runs go in
chunks; without an ``executor`` the chunks run one after another in this process, each on all
cores (rayon; ``threads`` is passed through). With any :class:`concurrent.futures.Executor` (a
``ProcessPoolExecutor``, dask's ``client.get_executor()``, ...) the module-level
:func:`vsinv.sweep.execute._run_chunk` is submitted per chunk (the base, the keys and the
chunk's values and seeds), a bounded number at a time (memory stays flat), and the results are
gathered in order. In worker processes pass ``threads`` (e.g. ``os.cpu_count() // workers``) to
avoid oversubscription. Process pools with any start method work whatever ran before in this
process: a forked worker starts its own rayon pools (vsinv's pools are per process, see
``src/parallel.rs``). A MuJoCo base (``[world] engine = "mujoco"``) runs its chunks through
:func:`vsinv.sim.run_batch`.

The package, one concern a module: :mod:`.distributions` (random axes), :mod:`.keys` (dotted and
derived keys), :mod:`.plan` (the runs and their seeds), :mod:`.execute` (chunks, executors,
progress), :mod:`.result` (the table), :mod:`.columns` (NumPy columns), :mod:`.plots`
(stability maps).
"""

from .distributions import Choice, Distribution, LogUniform, Uniform
from .execute import run_sweep
from .keys import DERIVED_KEYS, rotation_from_thetau, thetau_from_rotation
from .plan import build_scenarios, noise_seeds
from .result import SweepResult

__all__ = [
    "DERIVED_KEYS",
    "Choice",
    "Distribution",
    "LogUniform",
    "SweepResult",
    "Uniform",
    "build_scenarios",
    "noise_seeds",
    "rotation_from_thetau",
    "run_sweep",
    "thetau_from_rotation",
]
