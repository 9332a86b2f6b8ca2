"""Run a Monte Carlo study: chunks evaluated by the vectorised model, streamed to Parquet.

A :class:`Plan` fixes everything that determines the numbers (the configuration and its
hash, method, temperatures, sample count, chunk size, seed, sampling). Chunk k is
evaluated by :func:`evaluate_chunk`, a pure function of (plan, k): uniform scores from
:mod:`ecdsim.montecarlo.sampling`, values from the tolerances, one DeploymentSystem whose
toleranced fields are arrays, and one call of :func:`ecdsim.deployment.predict` at every
temperature at once. :func:`run` hands the chunks to an executor (in this process, or a
dask.distributed cluster), writes each finished chunk atomically as its own Parquet file,
and skips, on ``resume``, the chunks already on disk and valid. Because a chunk depends on
nothing but (plan, k), the results are the same for any number of workers and after any
number of interruptions.
"""

from __future__ import annotations

import contextlib
import ctypes
import datetime
import logging
import os
import sys
import threading
import time
from collections import Counter, deque
from collections.abc import Callable, Generator, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor, wait
from dataclasses import dataclass, field
from itertools import islice
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from ecdsim._version import __version__
from ecdsim.montecarlo import apply, sampling, store, streaming
from ecdsim.montecarlo.columns import output_column as output_column  # re-exported
from ecdsim.montecarlo.tolerances import ToleranceSet, resolve

if TYPE_CHECKING:
    from ecdsim.config import Config
    from ecdsim.deployment import Prediction
    from ecdsim.dynamics.params import DynamicParameters
    from ecdsim.model import DeploymentSystem
    from ecdsim.sizing.margin import MarginSettings
    from ecdsim.sizing.requirements import Requirements

# From this many samples, on a machine with at least LARGE_RUN_CPUS CPUs, a run with
# neither --workers nor --scheduler uses an embedded LocalCluster with one worker per CPU
# (docs/montecarlo.md), as issue 6 asks. On 2 CPUs the client and scheduler share the
# machine with the workers: 2 workers ran 10 million samples at 0.75x to 1.04x the
# in-process speed, about even; --workers 0 keeps a run in process.
LARGE_RUN_SAMPLES = 2_000_000
LARGE_RUN_CPUS = 2
# Chunks computed at once by the in-process path (--workers 0, or small runs), capped at
# the CPU count. On this project's shared 2-CPU machine (load average ~2 from other
# sessions), run() of 40 chunks took 2.7 to 3.4 s on two threads against 3.3 to 4.0 s on
# one (three alternating pairs); on a quiet machine the gain is larger.
IN_PROCESS_THREADS = 2
# Chunks computed in forked worker processes (InProcess.fork) only from this many after the
# first: forking and starting the workers costs some tens of milliseconds, which a few
# chunks of 65,536 samples (about 30 ms of CPU each) do not repay.
FORK_MIN_CHUNKS = 8
# Chunk writes waiting in line for the writer thread (run): a slow fsync then holds up
# the computation only when this many are behind. Each holds its chunk's columns
# (about 9 MB at 65,536 samples).
WRITE_QUEUE = 4
# Chunks held in memory at once, computed or waiting to be written (the memory estimate,
# ecdsim.montecarlo.budget).
CHUNKS_IN_FLIGHT = IN_PROCESS_THREADS + WRITE_QUEUE

OUTPUTS = {
    "deployment_time_s": "deployment_time",
    "end_speed_rad_s": "end_speed",
    "stalled": "stalled",
}
# With [requirements] in the config: the minimum torque margin over the travel
# (ecdsim.sizing.margin, docs/sizing.md section 5), per sample and temperature.
MARGIN = "min_torque_margin"


class _WriteSkipped(Exception):
    """A queued chunk write not made because an earlier write failed (run)."""


class RunError(Exception):
    """A study that cannot run as asked (user error); ``problems`` holds one line each."""

    def __init__(self, problems: list[str]) -> None:
        super().__init__("\n".join(problems))
        self.problems = problems


class RunInterrupted(Exception):
    """The run was stopped (Ctrl-C); every finished chunk is on disk and resumable.

    Attributes
    ----------
    out : the study's folder
    chunks_done : chunks on disk
    chunks_total : chunks in the study
    """

    def __init__(self, out: Path, chunks_done: int, chunks_total: int) -> None:
        super().__init__(f"interrupted with {chunks_done} of {chunks_total} chunks on disk")
        self.out = out
        self.chunks_done = chunks_done
        self.chunks_total = chunks_total


@dataclass(frozen=True)
class Plan:
    """Everything that determines a study's numbers.

    Attributes
    ----------
    system : the nominal deployment system (from the config)
    tolerances : the resolved tolerances and their correlation
    temperatures : analysis temperatures [degC]
    method : solver name (a key of ecdsim.methods.SOLVERS)
    samples : N, number of samples (parameter sets), each solved at every temperature
    chunk_size : samples per chunk (the last chunk may hold fewer)
    seed : the study's seed (>= 0)
    sampling : "random", "lhs" or "sobol"
    config_sha256 : hash of the configuration file's text
    config_source : where the configuration came from
    repeat_runs : runs of the repeatability study (the paper: 500)
    repeat_within : the spread they are compared with [s] (the paper: 0.5 s)
    dynamics : the dynamic parameters ([load] inertia ...), None if the config has none
    margin : how to compute the torque margin ([requirements.torque_margin]); None if the
        config has no [requirements] (no margin is computed then)
    required_margin : the smallest allowed torque margin [-] ([requirements]), if given
    requirements : the config's [requirements] (SI), for the probability of missing each
        (docs/qualification.md); None without that section
    """

    system: DeploymentSystem
    tolerances: ToleranceSet
    temperatures: tuple[float, ...]
    method: str
    samples: int
    chunk_size: int
    seed: int
    sampling: str
    config_sha256: str
    config_source: str
    repeat_runs: int = 500
    repeat_within: float = 0.5
    dynamics: DynamicParameters | None = None
    margin: MarginSettings | None = None
    required_margin: float | None = None
    requirements: Requirements | None = None

    @property
    def outputs(self) -> tuple[str, ...]:
        """The per-temperature outputs of each sample (column prefixes)."""
        return (*OUTPUTS, MARGIN) if self.margin is not None else tuple(OUTPUTS)

    @property
    def parameters(self) -> apply.Parameters:
        """The nominal model parameters."""
        return apply.Parameters(self.system, self.dynamics)

    def predict_options(self) -> dict[str, Any]:
        """Keyword arguments of ecdsim.deployment.predict besides system and temperatures."""
        options: dict[str, Any] = {"methods": (self.method,)}
        if self.dynamics is not None:
            options["dynamics"] = self.dynamics
        return options

    @property
    def chunks(self) -> int:
        """Number of chunks."""
        return -(-self.samples // self.chunk_size)

    def bounds(self, index: int) -> tuple[int, int]:
        """First sample of chunk ``index`` and one past its last."""
        start = index * self.chunk_size
        return start, min(start + self.chunk_size, self.samples)

    @property
    def output_columns(self) -> tuple[str, ...]:
        """The result columns, every output at every temperature."""
        return tuple(output_column(o, t) for t in self.temperatures for o in self.outputs)

    @property
    def summary_columns(self) -> tuple[str, ...]:
        """The columns the summary reads whole (for order statistics): the outputs.

        (The sample index is checked chunk by chunk where a chunk is read from its file.)
        """
        return self.output_columns

    @property
    def columns(self) -> tuple[str, ...]:
        """Every column of a chunk file, in order."""
        return ("sample", *self.tolerances.keys, *self.output_columns)

    def identity(self) -> dict[str, Any]:
        """What must match for a resumed run to continue this one."""
        return {
            "ecdsim_version": __version__,
            "config_sha256": self.config_sha256,
            "method": self.method,
            "temperatures_C": list(self.temperatures),
            "samples": self.samples,
            "chunk_size": self.chunk_size,
            "seed": self.seed,
            "sampling": self.sampling,
        }

    @property
    def identity_sha256(self) -> str:
        """Hash of the identity (stamped into every chunk file)."""
        return store.identity_hash(self.identity())


def build_plan(
    config: Config,
    samples: int,
    method: str = "exact",
    *,
    seed: int | None = None,
    sampling_method: str | None = None,
    chunk_size: int | None = None,
    temperatures: Sequence[float] | None = None,
    out: Path | None = None,
    resume: bool = False,
) -> Plan:
    """A plan from a configuration; arguments given here override its ``[tolerances]``.

    Without a seed (here or in the config) a resumed run takes the manifest's seed and a
    new run draws a fresh one (recorded in the manifest and the summary). A study that
    needs more memory, or (with ``out``) more disk, than this machine has is refused
    (:mod:`ecdsim.montecarlo.budget`).
    Raises :class:`ecdsim.config.ConfigError` or :class:`RunError` on bad input.
    """
    from ecdsim.config.seeds import seed_problem
    from ecdsim.config.tolerance_schema import DEFAULT_CHUNK_SIZE, SAMPLING_METHODS
    from ecdsim.methods import SOLVERS

    tolerances = resolve(config)
    spec = config.spec.tolerances
    assert spec is not None  # resolve() guarantees it
    problems = []
    if samples < 1:
        problems.append(f"--samples: {samples} must be >= 1")
    if method not in SOLVERS:
        problems.append(f"--method: {method!r} is not a method; expected one of {sorted(SOLVERS)}")
    chosen_sampling = sampling_method or spec.sampling
    if chosen_sampling not in SAMPLING_METHODS:
        problems.append(
            f"--sampling: {chosen_sampling!r} is not a sampling; expected one of "
            f"{list(SAMPLING_METHODS)}"
        )
    size = chunk_size if chunk_size is not None else spec.chunk_size or DEFAULT_CHUNK_SIZE
    if size < 1:
        problems.append(f"--chunk-size: {size} must be >= 1")
    elif chosen_sampling == "sobol" and size & (size - 1):
        problems.append(f"--chunk-size: {size}: sobol sampling needs a power of two, e.g. 65536")
    temps = tuple(float(t) for t in (temperatures or config.temperatures))
    if len(set(temps)) != len(temps):
        problems.append(f"temperatures repeat: {list(temps)} degC")
    if seed is not None and (bad_seed := seed_problem(seed)) is not None:
        problems.append(f"--seed {seed}: {bad_seed}")
    if problems:
        raise RunError(problems)
    chosen_seed = seed if seed is not None else spec.seed
    if chosen_seed is None and resume and out is not None:
        manifest = _manifest_or_error(out)
        if manifest is not None:
            chosen_seed = int(manifest["identity"]["seed"])
    if chosen_seed is None:
        chosen_seed = sampling.new_seed()
    plan = Plan(
        system=config.system,
        tolerances=tolerances,
        temperatures=temps,
        method=method,
        samples=samples,
        chunk_size=size,
        seed=chosen_seed,
        sampling=chosen_sampling,
        config_sha256=config.sha256,
        config_source=config.source,
        repeat_runs=spec.repeatability.runs,
        repeat_within=spec.repeatability.within,
        dynamics=config.spec.dynamics(),
        **_margin_settings(config),
    )
    # Refused here, before a folder is made or a chunk computed, rather than failing
    # hours later (or at once, deep in an allocation) for want of memory or disk.
    from ecdsim.montecarlo import budget

    too_large = budget.problems(plan, CHUNKS_IN_FLIGHT, out, resume)
    if too_large:
        raise RunError(too_large)
    return plan


def _margin_settings(config: Config) -> dict[str, Any]:
    """The torque-margin settings of the config's [requirements], if it has that section."""
    requirements = config.spec.requirements
    if requirements is None:
        return {}
    from ecdsim.sizing.requirements import Requirements

    resolved = Requirements.from_spec(requirements)
    return {
        "margin": resolved.margin,
        "required_margin": resolved.min_torque_margin,
        "requirements": resolved,
    }


@dataclass(frozen=True)
class ChunkResult:
    """One evaluated chunk.

    Attributes
    ----------
    index : chunk number
    columns : the chunk file's columns (inputs in SI, outputs per temperature)
    warnings : the model's warnings in this chunk: code, temperature, method, count, example
    version : ecdsim version of the process that computed it
    written : True if the worker already wrote the chunk file (columns then empty)
    sensitivity_sums : the chunk's sums for the sensitivity statistics, encoded
        (:mod:`ecdsim.montecarlo.streaming`), stored in the chunk file's metadata
    moments : the chunk's moments of the times and speeds, encoded
        (:func:`ecdsim.montecarlo.streaming.encode_moments`), stored beside them
    kept : True if a forked worker also copied the summary's columns into the study's
        shared whole columns (:func:`ecdsim.montecarlo.store.share_kept`)
    staged : the chunk file a forked worker wrote under a temporary name, for :func:`run`
        to sync and install (:func:`ecdsim.montecarlo.store.install_chunk`); "" if none
    """

    index: int
    columns: dict[str, np.ndarray[Any, Any]]
    warnings: list[dict[str, Any]]
    version: str
    written: bool = False
    sensitivity_sums: str = ""
    moments: str = ""
    kept: bool = False
    staged: str = ""


def chunk_values(plan: Plan, index: int) -> np.ndarray[Any, np.dtype[np.float64]]:
    """The toleranced quantities' values for chunk ``index``: shape (count, d) [SI]."""
    return chunk_scores_and_values(plan, index)[1]


def chunk_scores_and_values(
    plan: Plan, index: int
) -> tuple[np.ndarray[Any, np.dtype[np.float64]], np.ndarray[Any, np.dtype[np.float64]]]:
    """Chunk ``index``'s uniform scores after the copula, and its values, each (count, d)."""
    start, stop = plan.bounds(index)
    uniforms = sampling.uniforms(
        plan.sampling, plan.seed, plan.tolerances.dimension, plan.chunk_size, index, stop - start
    )
    scores = plan.tolerances.correlate(uniforms)
    return scores, plan.tolerances.values_of_scores(scores)


def outputs_of(plan: Plan, prediction: Prediction) -> dict[str, np.ndarray[Any, Any]]:
    """Each per-temperature output of a prediction, broadcast to its batch shape.

    Deployment time [s] (+inf where stalled), end speed [rad/s], the stall flag and, with
    margin settings, the minimum torque margin over the travel [-].
    """
    solution = prediction.solutions[plan.method]
    shape = prediction.problem.batch_shape
    found = {
        output: np.broadcast_to(getattr(solution, attribute), shape)
        for output, attribute in OUTPUTS.items()
    }
    if plan.margin is not None:
        from ecdsim.sizing.margin import margin_over_travel

        problem = prediction.problem
        lowest, _ = margin_over_travel(
            problem.angles,
            problem.torques,
            ecd_friction=prediction.ecd.ecd_friction,
            system_friction=prediction.system_friction,
            damping_rate=problem.damping_rate,
            stalled=solution.stalled,
            stall_angle=solution.stall_angle,
            settings=plan.margin,
            resistance=prediction.resistance,
            # A ground test's gravity (docs/sizing.md); None in flight, as before.
            gravity_amplitude=problem.gravity_amplitude if problem.has_gravity else None,
            gravity_angle=problem.gravity_angle if problem.has_gravity else None,
            forward_efficiency=(
                None
                if prediction.system.ecd.gearbox.efficiency is None
                else prediction.ecd.forward_efficiency
            ),
        ).minimum()
        found[MARGIN] = np.broadcast_to(lowest, shape)
    return found


def evaluate_chunk(plan: Plan, index: int) -> ChunkResult:
    """Sample chunk ``index`` and solve it at every temperature: a pure function of both."""
    from ecdsim.deployment import predict

    start, stop = plan.bounds(index)
    scores, values = chunk_scores_and_values(plan, index)
    keys = plan.tolerances.keys
    varied = apply.apply(plan.parameters, {key: values[:, j] for j, key in enumerate(keys)})
    temperatures = np.asarray(plan.temperatures, dtype=float)[:, np.newaxis]
    options = plan.predict_options()
    if varied.dynamics is not None:
        options["dynamics"] = varied.dynamics
    prediction = predict(varied.system, temperatures, **options)
    shape = (len(plan.temperatures), stop - start)
    columns: dict[str, np.ndarray[Any, Any]] = {"sample": np.arange(start, stop, dtype=np.int64)}
    for j, key in enumerate(keys):
        columns[key] = np.ascontiguousarray(values[:, j])
    for output, array in outputs_of(plan, prediction).items():
        full = np.broadcast_to(array, shape)
        for i, temperature in enumerate(plan.temperatures):
            # A view of the solution's row when it is solved contiguous (no copy).
            columns[output_column(output, temperature)] = np.ascontiguousarray(full[i])
    counts: Counter[tuple[str, float | None, str | None]] = Counter()
    examples: dict[tuple[str, float | None, str | None], str] = {}
    for warning in prediction.warnings:
        if warning.code == "stall":
            continue  # counted exactly, per sample, from the stalled columns
        where = (warning.code, warning.temperature_C, warning.method)
        counts[where] += 1
        examples.setdefault(where, warning.message)
    warnings = [
        {"code": c, "temperature_C": t, "method": m, "count": n, "example": examples[(c, t, m)]}
        for (c, t, m), n in sorted(counts.items(), key=lambda item: repr(item[0]))
    ]
    ordered = {name: columns[name] for name in plan.columns}
    sums = streaming.encode(streaming.chunk_sums(plan, ordered, scores, values))
    moments = streaming.encode_moments(streaming.chunk_moments(plan, ordered))
    return ChunkResult(
        index, ordered, warnings, __version__, sensitivity_sums=sums, moments=moments
    )


def write_result(plan: Plan, out: Path, result: ChunkResult) -> Path:
    """Write an evaluated chunk as its Parquet file, atomically, stamped with the plan
    (or install the file a forked worker staged for it)."""
    if result.staged:
        return store.install_chunk(out, result.index, Path(result.staged))
    return store.write_chunk(
        out, result.index, result.columns, plan.identity_sha256, _extra(plan, result)
    )


def _extra(plan: Plan, result: ChunkResult) -> dict[str, Any]:
    """What a chunk file's metadata holds besides the study's identity and its index:
    the version and config hash (also in the identity the hash stands for), each
    column's SI unit, and the chunk's warnings and streamed sums."""
    return {
        "ecdsim_version": __version__,
        "config_sha256": plan.config_sha256,
        "units": store.column_units(plan.columns, plan.tolerances),
        "warnings": result.warnings,
        streaming.KEY: result.sensitivity_sums,
        streaming.MOMENTS_KEY: result.moments,
    }


def evaluate_and_write(plan: Plan, index: int, out: Path) -> ChunkResult:
    """Evaluate chunk ``index`` and write its file here; return the result without columns.

    The task a LocalCluster worker runs: the file system is the client's, so the worker
    writes the file itself and only the small remainder travels back.
    """
    result = evaluate_chunk(plan, index)
    write_result(plan, out, result)
    return ChunkResult(
        index, {}, result.warnings, result.version, True, result.sensitivity_sums, result.moments
    )


class Executor(Protocol):
    """Evaluates chunks somewhere and yields them as they finish (in any order)."""

    def results(
        self, plan: Plan, indices: Sequence[int], out: Path
    ) -> Generator[ChunkResult, None, None]:
        """Evaluate the given chunks; yield each result once (written to ``out`` or not)."""
        ...

    def describe(self) -> str:
        """One line for the console."""
        ...


@dataclass(frozen=True)
class InProcess:
    """Evaluate the chunks in this process (vectorised within a chunk), on 1 or more threads.

    With ``threads`` > 1, that many chunks are computed at once on a thread pool: the
    compiled exact kernel, the random generator's shuffles and draws, the normal
    quantiles and NumPy's large operations release the GIL, so two threads use two
    cores for most of a chunk. Each chunk is still a pure function of (plan, index), and
    the results are yielded in index order, so the run is bit for bit the same as on one
    thread (tested). At most ``threads`` chunks are in flight, which bounds the memory.
    The first chunk is computed alone, so that lazy imports and the compiled kernel's
    loading happen on one thread.

    With ``fork`` (Linux), a run of at least FORK_MIN_CHUNKS further chunks computes them
    in ``threads`` child processes forked from this one instead (:func:`_forked_results`):
    the Python parts of a chunk (building the system, ``predict``, the sums) then run on
    every core at once instead of taking turns on the GIL, and each child encodes its own
    chunk files (this process's writer line syncs and installs them). The children
    inherit this process's state, imports and loaded kernels (no start-up of their own),
    so the chunks are the same function of (plan, index).

    Attributes
    ----------
    threads : chunks computed at once (1: one after another on the calling thread)
    fork : compute the chunks after the first in forked processes where possible
    """

    threads: int = 1
    fork: bool = False

    @property
    def forks(self) -> bool:
        """True if this executor computes chunks in forked workers (fork asked for and
        available, and more than one worker)."""
        return self.threads > 1 and self.fork and fork_available()

    def results(
        self, plan: Plan, indices: Sequence[int], out: Path
    ) -> Generator[ChunkResult, None, None]:
        """Evaluate each chunk (:func:`run` writes them), yielded in the order given."""
        pending = iter(indices)
        first = next(pending, None)
        if first is None:
            return
        if self.forks:
            rest = list(pending)
            if len(rest) >= FORK_MIN_CHUNKS:
                yield from _forked_results(plan, first, rest, out, self.threads)
                return
            pending = iter(rest)
        yield evaluate_chunk(plan, first)
        if self.threads <= 1:
            for index in pending:
                yield evaluate_chunk(plan, index)
            return
        _steady_heap()
        pool = ThreadPoolExecutor(max_workers=self.threads, thread_name_prefix="ecdsim-chunk")
        window: deque[Future[ChunkResult]] = deque(
            pool.submit(evaluate_chunk, plan, k) for k in islice(pending, self.threads)
        )
        try:
            while window:
                result = window.popleft().result()
                following = next(pending, None)
                if following is not None:
                    window.append(pool.submit(evaluate_chunk, plan, following))
                yield result
        finally:
            for future in window:
                future.cancel()
            pool.shutdown(wait=True)  # a chunk under way finishes (at most ~0.1 s)

    def describe(self) -> str:
        """One line for the console."""
        if self.forks:
            below = FORK_MIN_CHUNKS + 1
            return f"in process, {self.threads} forked workers (threads below {below} chunks)"
        if self.threads > 1:
            return f"in process, {self.threads} threads"
        return "in process"


def fork_available() -> bool:
    """True where chunk workers can be forked: Linux (fork is unsafe on macOS with its
    system libraries' threads, and absent on Windows)."""
    return sys.platform.startswith("linux") and hasattr(os, "fork")


# A forked child's study: set by _start_forked in the child (inherited, never pickled).
_FORKED: tuple[Plan, Path, dict[str, np.ndarray[Any, Any]]] | None = None


def _start_forked(
    plan: Plan, out: Path, shared: dict[str, np.ndarray[Any, Any]], parent: int
) -> None:
    """Initialise a forked chunk worker: its study, and no reaction to Ctrl-C.

    A terminal's Ctrl-C reaches the whole process group; the parent alone acts on it
    (it stops handing out chunks and waits for the ones under way, _forked_results).
    """
    import signal

    global _FORKED
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # Die with the parent: a parent killed outright (SIGKILL, the OOM killer) cannot shut
    # the pool down, and its workers would wait for tasks forever (each holds the task
    # pipe open for the others). PR_SET_PDEATHSIG = 1 (linux/prctl.h); then check that
    # the parent did not die before it was set.
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent:
        os._exit(1)
    _FORKED = (plan, out, shared)


def _forked_chunk(index: int) -> ChunkResult:
    """A forked worker's task: evaluate chunk ``index``, write its file under a temporary
    name, copy the summary's columns into the shared whole columns; return the rest.

    The file is synced and renamed by the parent's writer line (:func:`run`), in chunk
    order, so that the worker goes on computing while the disk catches up, and the
    chunks on disk after a failed write are exactly those before it, as in process.
    """
    assert _FORKED is not None, "not a forked chunk worker"
    plan, out, shared = _FORKED
    result = evaluate_chunk(plan, index)
    start, stop = plan.bounds(index)
    for name, whole in shared.items():
        whole[start:stop] = result.columns[name]
    staged = store.stage_chunk(
        out, index, result.columns, plan.identity_sha256, _extra(plan, result)
    )
    return ChunkResult(
        index,
        {},
        result.warnings,
        result.version,
        sensitivity_sums=result.sensitivity_sums,
        moments=result.moments,
        kept=bool(shared),
        staged=str(staged),
    )


def _forked_results(
    plan: Plan, first: int, rest: Sequence[int], out: Path, workers: int
) -> Generator[ChunkResult, None, None]:
    """Chunk ``first`` here, then ``rest`` in ``workers`` forked processes, in order.

    The first chunk is computed before the fork, so that the lazy imports and the
    compiled kernel's loading happen once and every child inherits them; the whole
    summary columns are allocated in shared memory before it too (store.share_kept),
    and no thread of this module runs yet (the chunk writer starts when the first
    result is handed out), so no child inherits a lock held by one. At most
    2 * ``workers`` chunks are handed out ahead, which bounds the memory; results are
    yielded in the order given. On an error or Ctrl-C here, the chunks not started are
    cancelled and those under way finish (each stages its whole file or none; run()
    removes what is staged and not installed).
    """
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    head = evaluate_chunk(plan, first)
    _steady_heap()  # inherited by the children (glibc's settings are process memory)
    summary = {name: head.columns[name] for name in plan.summary_columns}
    shared = store.share_kept(out, plan.identity_sha256, summary)
    pool = ProcessPoolExecutor(
        max_workers=workers,
        mp_context=multiprocessing.get_context("fork"),
        initializer=_start_forked,
        initargs=(plan, out.resolve(), shared, os.getpid()),
    )
    pending = iter(rest)
    window: deque[Future[ChunkResult]] = deque()
    try:
        window.extend(pool.submit(_forked_chunk, k) for k in islice(pending, 2 * workers))
        yield head
        while window:
            result = window.popleft().result()
            following = next(pending, None)
            if following is not None:
                window.append(pool.submit(_forked_chunk, following))
            yield result
    finally:
        pool.shutdown(wait=True, cancel_futures=True)  # chunks under way finish


@dataclass(frozen=True)
class DaskExecutor:
    """Evaluate chunks on dask.distributed: an embedded LocalCluster or a running scheduler.

    The workers only compute; this process receives each finished chunk and writes it,
    so a remote cluster needs no shared file system (only ecdsim, same version, installed
    on its workers). At most ``window`` chunks are in flight, which bounds memory and
    lets Ctrl-C stop the run quickly.

    Attributes
    ----------
    workers : LocalCluster worker count (ignored with an address)
    address : a running scheduler's address, e.g. "tcp://10.0.0.5:8786"; None for local
    processes : LocalCluster workers as processes (True) or threads of this process
    window : chunks in flight; default twice the worker count, at least 4
    connect_timeout : how long to try to reach a scheduler, e.g. "20s"
    """

    workers: int = 1
    address: str | None = None
    processes: bool = True
    window: int | None = None
    connect_timeout: str = "20s"

    def describe(self) -> str:
        """One line for the console."""
        if self.address:
            return f"dask scheduler {self.address}"
        kind = "processes" if self.processes else "threads"
        return f"dask LocalCluster, {self.workers} worker {kind}"

    @contextlib.contextmanager
    def _client(self) -> Iterator[Any]:
        distributed = store.require("distributed")
        quiet_cancel_race()
        if self.address:
            try:
                client = distributed.Client(self.address, timeout=self.connect_timeout)
            except (OSError, TimeoutError, ValueError) as exc:
                raise RunError(
                    [f"--scheduler: cannot connect to {self.address!r} ({exc})"]
                ) from None
            try:
                yield client
            finally:
                client.close()
            return
        dask = store.require("dask")
        # dask starts worker processes with MALLOC_TRIM_THRESHOLD_=65536 (and leaves it in
        # this process's environment, which later workers inherit). Setting it turns off
        # glibc's adaptive mmap threshold, so every large NumPy temporary becomes a fresh
        # mmap that page-faults on first touch: a 65 536-sample chunk took 2x as long in a
        # worker as in this process (4x the page faults). A fixed mmap threshold of
        # 128 MiB keeps the chunk's arrays on the reused heap whatever the trim setting;
        # chunks bound the memory anyway.
        environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", default={}))
        environ.pop("MALLOC_TRIM_THRESHOLD_", None)
        environ["MALLOC_MMAP_THRESHOLD_"] = 128 * 2**20
        try:
            with dask.config.set({"distributed.nanny.pre-spawn-environ": environ}):
                cluster = distributed.LocalCluster(
                    n_workers=self.workers,
                    threads_per_worker=1,
                    processes=self.processes,
                    # Port 0: any free port, so that a busy 8787 (another cluster's dashboard)
                    # neither fails nor warns.
                    dashboard_address=":0",
                    silence_logs=logging.ERROR,
                )
        except Exception as exc:  # noqa: BLE001 - dask raises plain RuntimeError and others
            raise RunError(
                [f"--workers {self.workers}: cannot start a LocalCluster ({exc})"]
            ) from None
        try:
            client = distributed.Client(cluster)
            try:
                if self.processes:
                    # A terminal's Ctrl-C reaches the whole process group; only this
                    # process should act on it (cancel, close the cluster, report).
                    client.run(_ignore_interrupts)
                yield client
            finally:
                client.close()
        finally:
            cluster.close()

    def results(
        self, plan: Plan, indices: Sequence[int], out: Path
    ) -> Generator[ChunkResult, None, None]:
        """Submit the chunks (a bounded window at a time) and yield them as they finish.

        LocalCluster workers share this machine's file system and write their chunk
        files themselves; a remote cluster's workers send the columns back for this
        process to write (no shared file system needed).
        """
        distributed = store.require("distributed")
        target = out.resolve()
        with self._client() as client:
            workers = max(1, len(client.scheduler_info().get("workers", {})))
            window = self.window or max(4, 2 * workers)
            [shared] = client.scatter([plan], broadcast=True, hash=False)

            def submit(index: int) -> Any:
                if self.address is None:
                    return client.submit(evaluate_and_write, shared, index, target, pure=False)
                return client.submit(evaluate_chunk, shared, index, pure=False)

            pending = iter(indices)
            running = distributed.as_completed([submit(k) for k in islice(pending, window)])
            try:
                for future in running:
                    result: ChunkResult = future.result()
                    following = next(pending, None)
                    if following is not None:
                        running.add(submit(following))
                    yield result
            finally:
                for future in list(running.futures):
                    future.cancel()


class _CancelRaceFilter(logging.Filter):
    """Drop tornado's report of a race in ``distributed.utils.sync`` on Ctrl-C.

    ``sync()`` (distributed 2026.8.0) declares its ``future`` without a value and, on a
    KeyboardInterrupt, schedules a ``cancel`` callback that reads it. When Ctrl-C comes
    before the coroutine has assigned it, ``cancel`` raises NameError ("cannot access
    free variable 'future'") and tornado logs it with a traceback, although nothing is
    wrong: the run stops as asked and says how to resume. Only that record is dropped
    (a NameError raised in a function ``cancel`` of ``distributed/utils.py``).
    """

    def filter(self, record: logging.LogRecord) -> bool:
        error = record.exc_info[1] if record.exc_info else None
        if not isinstance(error, NameError) or error.__traceback__ is None:
            return True
        frame = error.__traceback__
        while frame.tb_next is not None:
            frame = frame.tb_next
        code = frame.tb_frame.f_code
        path = Path(code.co_filename)
        return not (code.co_name == "cancel" and path.parts[-2:] == ("distributed", "utils.py"))


_CANCEL_RACE_FILTER = _CancelRaceFilter()


def quiet_cancel_race() -> None:
    """Install :class:`_CancelRaceFilter` on tornado's callback logger (once; it stays,
    since the callback may run after the client is closed)."""
    logger = logging.getLogger("tornado.application")
    if _CANCEL_RACE_FILTER not in logger.filters:
        logger.addFilter(_CANCEL_RACE_FILTER)


def _ignore_interrupts() -> None:
    """Make a LocalCluster worker process ignore SIGINT (run on each worker)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


# --workers accepts up to one LocalCluster worker per CPU, and never fewer than this many
# (so that a run can be tried with real workers on any machine).
MIN_WORKERS_ALLOWED = 4


def workers_limit() -> int:
    """The most ``--workers`` accepted here: one per CPU, at least :data:`MIN_WORKERS_ALLOWED`.

    Each LocalCluster worker is a process of its own (an interpreter with NumPy, ecdsim,
    dask and its chunk's arrays: about 310 MB resident each, measured with two workers
    on 3,000,000 samples); workers beyond one per CPU only take turns on the same CPUs,
    so they add memory and no speed (``--workers 100000`` started processes until the
    memory ran out).
    """
    return max(os.cpu_count() or 1, MIN_WORKERS_ALLOWED)


def choose_executor(samples: int, workers: int | None, scheduler: str | None) -> Executor:
    """The executor for ``--workers`` / ``--scheduler``; large runs default to a LocalCluster.

    ``workers=0`` forces the in-process path. Without either option, runs of at least
    LARGE_RUN_SAMPLES samples on a machine with at least LARGE_RUN_CPUS CPUs use a
    LocalCluster with one worker per CPU when dask.distributed is installed, and the
    in-process path otherwise; except where the in-process path already has one forked
    worker per CPU (Linux, CPUs <= IN_PROCESS_THREADS): there it uses every CPU without a
    scheduler and a client beside the workers, and was 1.9x faster than the LocalCluster
    on this project's 2-CPU machine (10,000,000 samples, three interleaved pairs: 4.4 to
    5.6 s against 8.2 to 9.0 s).
    """
    if workers is not None and scheduler is not None:
        raise RunError(["give either --workers or --scheduler, not both"])
    if scheduler is not None:
        return DaskExecutor(address=scheduler)
    cpus = os.cpu_count() or 1
    if workers is not None:
        if not 0 <= workers <= workers_limit():
            raise RunError(
                [
                    f"--workers {workers}: expected 0 (in this process) to {workers_limit()}: "
                    "each worker is a process of about 300 MB, and more workers than CPUs "
                    f"({cpus} here) add memory, not speed"
                ]
            )
        return in_process() if workers == 0 else DaskExecutor(workers=workers)
    local = in_process()
    if local.forks and local.threads >= cpus:
        return local
    if samples >= LARGE_RUN_SAMPLES and cpus >= LARGE_RUN_CPUS:
        try:
            store.require("distributed")
        except store.MissingDependency:
            return in_process()
        return DaskExecutor(workers=cpus)
    return in_process()


def _steady_heap() -> None:
    """Keep a chunk's large temporaries on glibc's reused heap (no-op elsewhere).

    glibc gives each thread its own arena; by default it maps every large block afresh
    (its adaptive mmap threshold) and trims the heaps as soon as 128 KiB are free, so a
    chunk's 0.5 MB arrays were page-faulted in anew: in a 30-chunk test two threads took
    70,000 to 140,000 page faults against about 10,000 for one; the fixed thresholds
    halve them. A fixed mmap threshold and trim
    threshold of 128 MiB (as the LocalCluster workers get, DaskExecutor) keep the
    arrays on the heap; the chunks bound the memory anyway. Process-wide, once.
    """
    global _HEAP_STEADY
    if _HEAP_STEADY or not sys.platform.startswith("linux"):
        return
    _HEAP_STEADY = True
    try:
        libc = ctypes.CDLL(None)
        mallopt = libc.mallopt
    except (OSError, AttributeError):  # not glibc (musl has no mallopt)
        return
    mallopt(_M_MMAP_THRESHOLD, 128 * 2**20)
    mallopt(_M_TRIM_THRESHOLD, 128 * 2**20)


_HEAP_STEADY = False
_M_TRIM_THRESHOLD = -1  # glibc malloc.h
_M_MMAP_THRESHOLD = -3


def in_process() -> InProcess:
    """The in-process executor on min(IN_PROCESS_THREADS, CPUs) threads, or as many
    forked worker processes where fork is available (InProcess)."""
    return InProcess(
        threads=max(1, min(IN_PROCESS_THREADS, os.cpu_count() or 1)), fork=fork_available()
    )


@dataclass(frozen=True)
class RunReport:
    """What a run did.

    Attributes
    ----------
    out : the study's folder
    chunks_total : chunks in the study
    chunks_computed : chunks computed by this run
    chunks_reused : valid chunks found on disk and kept (resume)
    elapsed_s : wall time of this run [s]
    executor : where the chunks were computed
    notes : remarks for the console (stale files removed, nothing to resume, ...)
    """

    out: Path
    chunks_total: int
    chunks_computed: int
    chunks_reused: int
    elapsed_s: float
    executor: str
    notes: list[str] = field(default_factory=list)


def _manifest_or_error(out: Path) -> dict[str, Any] | None:
    try:
        return store.read_manifest(out)
    except ValueError as exc:
        raise RunError([str(exc)]) from None


def _prepare(plan: Plan, out: Path, resume: bool, notes: list[str]) -> bool:
    """Check or write the manifest; True if this call created it."""
    manifest = _manifest_or_error(out)
    if manifest is not None and not resume:
        raise RunError(
            [
                f"--out {out}: this folder already holds a Monte Carlo run; add --resume to "
                "continue it, or choose another --out"
            ]
        )
    if manifest is not None:
        recorded = manifest.get("identity", {})
        wanted = plan.identity()
        differences = [
            f"--resume: {out / store.MANIFEST} has {key} = {recorded.get(key)!r}, this run "
            f"has {value!r}"
            for key, value in wanted.items()
            if recorded.get(key) != value
        ]
        if differences:
            raise RunError(
                [*differences, "a resumed run must repeat the original command and config"]
            )
        return False
    if resume:
        notes.append(f"nothing to resume in {out}: starting a new run")
    store.write_manifest(
        out,
        plan.identity(),
        {
            "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
            "config_source": plan.config_source,
            "chunks": plan.chunks,
            "columns": list(plan.columns),
            "tolerances": plan.tolerances.to_dict(),
            "correlation": [list(row) for row in plan.tolerances.correlation],
        },
    )
    return True


def _make_folders(out: Path) -> list[Path]:
    """Create the run's folder and its chunks folder; the folders that did not exist,
    outermost first (the caller says so: ``ecdsim montecarlo`` once the run stands, and
    a report's study in a temporary folder not at all)."""
    from ecdsim import atomic

    made = atomic.make_folder(out, announce=False)
    chunks = out / store.CHUNKS
    if not chunks.exists():
        chunks.mkdir()
        made.append(chunks)
    return made


def _remove_empty(folders: list[Path]) -> None:
    """Remove ``folders`` (made by :func:`_make_folders`), innermost first, where empty."""
    for folder in reversed(folders):
        with contextlib.suppress(OSError):  # not empty (a user's file), or gone
            folder.rmdir()


def run(
    plan: Plan,
    out: Path,
    executor: Executor | None = None,
    *,
    resume: bool = False,
    progress: Callable[[int, int], None] | None = None,
) -> RunReport:
    """Evaluate every chunk of the plan not yet on disk, writing each as it finishes.

    ``progress(samples_done, samples_total)`` is called once at the start and after each
    chunk. A KeyboardInterrupt stops the run and raises :class:`RunInterrupted`: the
    finished chunks stay on disk, the manifest stays valid, and ``resume=True`` continues.
    """
    started = time.perf_counter()
    chosen = executor or InProcess()
    notes: list[str] = []
    out = Path(out)
    made = _make_folders(out)
    try:
        created = _prepare(plan, out, resume, notes)
    except BaseException:
        _remove_empty(made)
        raise
    removed = store.remove_partial_files(out)
    if removed:
        notes.append(f"removed {len(removed)} unfinished file(s) left by an interrupted run")
    identity = plan.identity_sha256
    done: list[int] = []
    todo: list[int] = []
    for k in range(plan.chunks):
        start, stop = plan.bounds(k)
        valid = resume and store.chunk_is_valid(out, k, identity, stop - start, plan.columns)
        (done if valid else todo).append(k)
    samples_done = sum(plan.bounds(k)[1] - plan.bounds(k)[0] for k in done)
    if progress:
        progress(samples_done, plan.samples)
    computed = 0
    # The chunk files are written by one writer thread, one file at a time and in chunk
    # order, while this thread takes the next chunks: the Parquet encoding and the fsync
    # release the GIL, so the disk's time overlaps the computation. Up to WRITE_QUEUE
    # writes wait in line (their columns bound the memory), so that a slow fsync does not
    # hold up the computation. A write that fails (ENOSPC, Ctrl-C) stops the line: the
    # writes queued behind it see ``stopped`` and write nothing, so every chunk before the
    # failed one is on disk and none after it.
    writer = ThreadPoolExecutor(max_workers=1, thread_name_prefix="ecdsim-chunk-writer")
    stopped = threading.Event()
    queued: deque[tuple[Future[Any], ChunkResult]] = deque()

    def write_in_line(result: ChunkResult) -> None:
        if stopped.is_set():
            if result.staged:
                Path(result.staged).unlink(missing_ok=True)
            raise _WriteSkipped
        try:
            write_result(plan, out, result)
        except BaseException:
            stopped.set()
            raise

    store.start_keeping(out, identity, plan.samples)

    def finished(result: ChunkResult) -> None:
        nonlocal computed, samples_done
        if result.columns:
            kept = {name: result.columns[name] for name in plan.summary_columns}
            store.keep(out, identity, result.index, plan.bounds(result.index)[0], kept)
        elif result.kept:
            store.mark_kept(out, identity, result.index, plan.bounds(result.index)[0])
        computed += 1
        start, stop = plan.bounds(result.index)
        samples_done += stop - start
        if progress:
            progress(samples_done, plan.samples)

    def settle(keep_waiting: int) -> None:
        """Take the finished writes, in order, until at most ``keep_waiting`` are queued."""
        while queued and (len(queued) > keep_waiting or queued[0][0].done()):
            future, result = queued.popleft()
            future.result()  # re-raises the write's error (ENOSPC, Ctrl-C) here
            finished(result)

    def stop_writing() -> None:
        stopped.set()
        wait([future for future, _ in queued])  # a write under way finishes or fails

    try:
        with contextlib.closing(chosen.results(plan, todo, out)) as results:
            for result in results:
                if result.version != __version__:
                    raise RunError(
                        [
                            f"a worker runs ecdsim {result.version}, this process {__version__}; "
                            "install the same version on every worker"
                        ]
                    )
                settle(WRITE_QUEUE - 1)
                if result.written:
                    finished(result)
                else:
                    queued.append((writer.submit(write_in_line, result), result))
            settle(0)
    except KeyboardInterrupt:
        stop_writing()
        # ecdsim.atomic removes its temporary file when the write is interrupted, except
        # in the instant between creating it and entering its try block: sweep up.
        store.remove_partial_files(out)
        on_disk = sum(store.chunk_path(out, k).exists() for k in range(plan.chunks))
        raise RunInterrupted(out, on_disk, plan.chunks) from None
    except Exception:
        stop_writing()
        store.remove_partial_files(out)  # files staged by forked workers, not installed
        if created and computed == 0:
            # Nothing was computed (no scheduler, a missing package, a bad first chunk):
            # leave no half-started run behind, so that the same command can be repeated,
            # nor the folders this run made for it (docs: a failed run writes nothing).
            (out / store.MANIFEST).unlink(missing_ok=True)
            _remove_empty(made)
        raise
    finally:
        writer.shutdown(wait=True)
    return RunReport(
        out=out,
        chunks_total=plan.chunks,
        chunks_computed=computed,
        chunks_reused=len(done),
        elapsed_s=time.perf_counter() - started,
        executor=chosen.describe(),
        notes=notes,
    )
