"""Seeded CMA-ES minimisation with serial, process-pool or Dask evaluation (thesis ch. 4.7).

:func:`cma_es` minimises any scalar ``objective(x)`` with the covariance matrix adaptation evolution strategy of the
``cma`` package (ask/tell loop), evaluating each generation's candidates in parallel.  It is used to tune impedance
parameters against the fitness (4.49), the mean of ``|f_d - f_k|`` over a run.  A run ends on cma's own termination
criteria (``tol_fun``, ``tol_x`` and cma's defaults) or on a cap (``max_generations``, ``max_evaluations``);
:attr:`~bhgrasp.tuning.result.TuningResult.criteria` is cma's ``stop()`` dictionary, saying which fired.

Evaluation runs in a :class:`~concurrent.futures.ProcessPoolExecutor` created for the run (default), in-process
(``executor="serial"``), or on any :class:`~concurrent.futures.Executor`, e.g. a Dask
``distributed.Client.get_executor()``.  Results are collected in candidate order, never completion order, and the
sampling uses a generator private to the run, so the same seed and objective give a bitwise identical
:class:`TuningResult` whatever the executor.

A :class:`BatchedObjective` evaluates many candidates per call (e.g. one :class:`~bhgrasp.sim.batch.BatchSimulator`
per call, one task of the executor each); since a batch gives the bits of separate runs, the result is the same.

A candidate whose evaluation raises, or returns NaN/inf or a non-number, is recorded (``failures``, fitness
``inf`` in the history) and handed to CMA-ES with a finite penalty; if a whole generation fails, or the executor
itself breaks, :class:`TuningError` is raised carrying the result so far.  (A Dask task that kills its workers
ends with ``KilledWorker``; the cluster survives, so that counts as a failed candidate.)  ``cma``, ``tqdm`` and
the process pool are imported only when :func:`cma_es` runs.
"""

from bhgrasp.tuning.cma import BatchedObjective, cma_es
from bhgrasp.tuning.result import TuningError, TuningResult

__all__ = ["BatchedObjective", "TuningError", "TuningResult", "cma_es"]
