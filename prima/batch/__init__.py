"""Many runs at once, on this machine or a cluster: ``prima sweep`` and ``prima check``.

A batch is a list of :class:`Job` (a scenario's :class:`Bundle` swept: its runs,
seed, jitter, thresholds, and what else a run's record says, an :class:`Analysis`).
:func:`dispatch` sends the runs in :class:`Chunk` of runs to a :class:`Pool`, one
:class:`concurrent.futures.Executor` seam: :class:`Inline` (this process),
:class:`Processes` (this machine's cores, the default) or a Dask cluster
(:func:`pool_for` with ``dask://HOST:PORT``; the ``dask`` extra; waited for no longer
than :class:`ClusterTimeouts` say, from the environment: :data:`TIMEOUTS`). Every run's record
comes back in the order of the runs, the same whatever ran it; a lost chunk is
sent again. :class:`ResultsFile` writes them as they come and reads them back to
resume a batch.
"""

from prima.batch._dispatch import (
    CHUNK,
    Inline,
    Pool,
    Processes,
    chunk_size,
    collect,
    dispatch,
    plan,
)
from prima.batch._pools import executor_problem, pool_for
from prima.batch._timeouts import TIMEOUTS, ClusterTimeouts
from prima.batch._records import Nullable, shape_problem
from prima.batch._results import ResultsFile
from prima.batch._variants import (
    MIN_ANSWER_DELAY,
    Bundle,
    bundle_scenario,
    number,
    repath,
    rng,
    shift_timings,
    switched_root,
    write_variant,
)
from prima.batch._work import CPU, Analysis, Chunk, Job, Observer, record_of, run_chunk, run_one

__all__ = [
    "CHUNK",
    "CPU",
    "MIN_ANSWER_DELAY",
    "TIMEOUTS",
    "Analysis",
    "Bundle",
    "Chunk",
    "ClusterTimeouts",
    "Inline",
    "Job",
    "Nullable",
    "Observer",
    "Pool",
    "Processes",
    "ResultsFile",
    "bundle_scenario",
    "chunk_size",
    "collect",
    "dispatch",
    "executor_problem",
    "number",
    "plan",
    "pool_for",
    "record_of",
    "repath",
    "rng",
    "run_chunk",
    "run_one",
    "shape_problem",
    "shift_timings",
    "switched_root",
    "write_variant",
]
