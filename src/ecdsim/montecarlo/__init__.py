"""Monte Carlo tolerance studies: percentiles, stall probability and sensitivities at scale.

The pieces, each in its own module (user guide: docs/montecarlo.md):

* :mod:`~ecdsim.montecarlo.tolerances`: the ``[tolerances]`` section resolved against the
  configuration, uniform scores -> parameter values (with a Gaussian copula);
* :mod:`~ecdsim.montecarlo.sampling`: random, Latin hypercube and Sobol designs, generated
  chunk by chunk from the seed and the chunk index alone;
* :mod:`~ecdsim.montecarlo.apply`: sampled values -> a DeploymentSystem of arrays;
* :mod:`~ecdsim.montecarlo.run`: chunk evaluation (one vectorised ``predict`` per chunk),
  in process or on dask.distributed, streamed to Parquet, resumable;
* :mod:`~ecdsim.montecarlo.stats` and :mod:`~ecdsim.montecarlo.repeatability`: the
  statistics, on the ranks and intervals of :mod:`~ecdsim.montecarlo.intervals`;
  :mod:`~ecdsim.montecarlo.plots`: histogram, CDF and tornado plots;
* :mod:`~ecdsim.montecarlo.samples`: ``ecdsim.montecarlo.open(folder)``, a finished
  study's samples as a pandas DataFrame (or a pyarrow dataset) for notebooks.

pandas, pyarrow and dask are optional (``pip install 'ecdsim[montecarlo]'``) and are
imported only when a study runs.
"""

from ecdsim.montecarlo.run import (
    DaskExecutor,
    InProcess,
    Plan,
    RunError,
    RunInterrupted,
    RunReport,
    build_plan,
    choose_executor,
    evaluate_chunk,
    run,
)
from ecdsim.montecarlo.samples import NotAStudy
from ecdsim.montecarlo.samples import open_samples as open
from ecdsim.montecarlo.store import MissingDependency
from ecdsim.montecarlo.tolerances import Tolerance, ToleranceSet, resolve

__all__ = [
    "DaskExecutor",
    "InProcess",
    "MissingDependency",
    "NotAStudy",
    "Plan",
    "RunError",
    "RunInterrupted",
    "RunReport",
    "Tolerance",
    "ToleranceSet",
    "build_plan",
    "choose_executor",
    "evaluate_chunk",
    "open",
    "resolve",
    "run",
]
