"""The dynamic kernel compiled from its own source, or run as plain Python.

The kernel's modules (this package, and the laws of :mod:`ecdsim.physics` they call)
are plain Python written in the subset numba compiles: functions of floats, ints, tuples
and NumPy arrays. :func:`backend` gives the entry points in one of two forms, built
from the same functions:

* ``"numba"`` (the default): each function is compiled with ``numba.njit``. Its globals
  are copied and every kernel or physics function they name is replaced by its compiled
  form, recursively (a compiled function can only call compiled ones), the way
  CalebBell/fluids builds its numba versions from the Python source. The functions that
  a step evaluates many times (:data:`INLINE`), and every law of :mod:`ecdsim.physics`,
  are inlined into their callers in numba's IR, so that their arrays and values stay in
  registers between stages (the laws as calls had cost a third to a half of a batch's
  time: 252 against 135 us per roll-off deployment, measured on a loaded 2-core
  machine); the rest are ordinary calls. Compiled code is cached on disk (numba's
  ``cache=True``) under a key that includes a digest of every kernel and physics source
  file, so that editing a law in :mod:`ecdsim.physics` recompiles the kernels that
  inline it (numba itself checks only the calling function's own file).
* ``"python"``: the same functions uncompiled (slow, identical in logic): used without
  numba or with ``ECDSIM_NUMBA=0``, and by the tests that hold the two together.

numba is imported here, on the first dynamic solve, never at start-up, through
:mod:`ecdsim._numba` (the one switch, the compile notice and count, the cache folder
rules of a read-only install: ``ecdsim precompile`` compiles these kernels ahead).
"""

from __future__ import annotations

import hashlib
import types
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any

from ecdsim import _numba

# The kernel's modules and the physics modules whose functions it compiles.
KERNEL_PACKAGE = "ecdsim.dynamics.kernel"
PHYSICS_PACKAGE = "ecdsim.physics"
# Models built on the kernel (their functions compiled with it, by :func:`substituted`);
# named, not imported: they sit in a layer above.
MODEL_PACKAGES = ("ecdsim.wing.kernel",)
# Functions inlined into their callers when compiled: the right-hand side, Jacobian and
# stage solve of a step, and the laws they evaluate (numba counts references to every
# array passed between compiled functions with atomic operations; inlined, the stage
# values stay in registers: docs/architecture.md, the dynamic kernel).
INLINE = frozenset(
    {
        "derivatives",
        "jacobian",
        "hinge_forces",
        "stage_solve",
        "attempt",  # one call site each (advance_integrated): inlined, a step passes
        "_earliest",  # its arrays in registers, not as copies on the stack
        "factorize",
        "error_norm",
        "step_factor",
        "excess_at",
        "factor_at",
        "load_spring",
        "mesh_now",
        "event_value",
        "crossed",
        "_endpoint",
        "_extremes",
        "registered_terms",  # the registered effects' sums (kernel/effects.py)
        "registered_torque",
    }
)


# Functions that allocate arrays, compiled with numba's reference-counted memory (NRT);
# every other kernel function is compiled without it, so that passing the case's arrays
# between functions costs no atomic reference counting (it had cost a quarter of a step).
ALLOCATING = frozenset({"solve_cases", "new_workspace"})


def numba_requested() -> bool:
    """False when ``ECDSIM_NUMBA=0`` asks for the plain-Python kernel (the switch every
    compiled kernel obeys: :func:`ecdsim._numba.switched_off`)."""
    return not _numba.switched_off()


@cache
def source_digest() -> str:
    """SHA-256 of every kernel and physics source file (the compiled code's real inputs)."""
    root = Path(__file__).resolve().parents[2]
    digest = hashlib.sha256()
    for folder in ("dynamics/kernel", "physics", "wing/kernel"):
        for path in sorted((root / folder).glob("*.py")):
            digest.update(path.name.encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


def _ours(value: object) -> bool:
    """A plain function of the kernel or of the physics package."""
    if not isinstance(value, types.FunctionType):
        return False
    module = value.__module__ or ""
    return module.startswith((KERNEL_PACKAGE, PHYSICS_PACKAGE, *MODEL_PACKAGES))


def _copy_with_globals(func: Callable[..., Any]) -> tuple[types.FunctionType, dict[str, Any]]:
    """A copy of ``func`` with a namespace of its own (a copy of its module's globals),
    so that the names it calls can be pointed at other functions."""
    namespace = dict(func.__globals__)
    copy = types.FunctionType(
        func.__code__, namespace, func.__name__, func.__defaults__, func.__closure__
    )
    copy.__qualname__ = func.__qualname__
    copy.__module__ = func.__module__
    return copy, namespace


def _point_globals(
    namespace: dict[str, Any],
    substitutes: dict[str, Callable[..., Any]],
    convert: Callable[[Callable[..., Any]], Any],
    compile_substitutes: bool,
) -> None:
    """Point a copy's globals at the substitutes (converted too when
    ``compile_substitutes``) and every kernel or physics function at its converted copy."""
    for name, value in list(namespace.items()):
        if name in substitutes:
            given = substitutes[name]
            namespace[name] = convert(given) if compile_substitutes else given
        elif _ours(value):
            namespace[name] = convert(value)


class _Compiler:
    """Compiled copies of kernel functions, each calling the compiled copies of its own.

    With ``substitutes`` (a model other than the hinge: the wing) the named globals are
    replaced by the given functions in every copy, every copy is compiled with numba's
    reference-counted memory, and ``tag`` keeps its cache entries apart."""

    def __init__(
        self, substitutes: dict[str, Callable[..., Any]] | None = None, tag: str = ""
    ) -> None:
        # numba with ecdsim's compile notice and compile count (ecdsim._numba).
        self._numba: Any = _numba.load()
        self._done: dict[Callable[..., Any], Any] = {}
        self._substitutes = substitutes or {}
        self._tag = tag

    def __call__(self, func: Callable[..., Any]) -> Any:
        done = self._done.get(func)
        if done is not None:
            return done
        copy, namespace = _copy_with_globals(func)
        law = (func.__module__ or "").startswith(PHYSICS_PACKAGE)
        inline = "always" if func.__name__ in INLINE or law else "never"
        nrt = func.__name__ in ALLOCATING or bool(self._substitutes)
        njit: Any = self._numba.njit  # _nrt: numba's own option (ALLOCATING), not in its stubs
        dispatcher = njit(nogil=True, error_model="numpy", inline=inline, _nrt=nrt)(copy)
        dispatcher._cache = _digest_cache(self._numba, self._tag)(copy)  # cache=True, keyed
        _numba.note_cache(dispatcher._cache.cache_path)
        self._done[func] = dispatcher
        _point_globals(namespace, self._substitutes, self, compile_substitutes=True)
        return dispatcher


@cache
def _digest_cache(numba: Any, tag: str = "") -> type:
    """numba's function cache with the sources' digest (and a model's tag) in every
    entry's key."""
    from numba.core.caching import FunctionCache

    class DigestCache(FunctionCache):
        def _index_key(self, sig: Any, codegen: Any) -> Any:
            base: tuple[Any, ...] = super()._index_key(sig, codegen)  # type: ignore[no-untyped-call]
            return (*base, source_digest(), tag)

    return DigestCache


class Backend:
    """The kernel's entry points in one form: ``name`` is ``"numba"`` or ``"python"``."""

    def __init__(self, name: str, convert: Callable[[Callable[..., Any]], Any]) -> None:
        self.name = name
        self._convert = convert
        self._entries: dict[str, Any] = {}

    def __getattr__(self, attr: str) -> Any:
        if attr.startswith("_"):
            raise AttributeError(attr)
        found = self._entries.get(attr)
        if found is None:
            from ecdsim.dynamics.kernel import entry

            found = self._convert(getattr(entry, attr))
            self._entries[attr] = found
        return found


class _Substituter:
    """Plain copies of kernel functions whose globals name some substituted functions
    (every kernel function is copied, its globals pointing at the copies)."""

    def __init__(self, substitutes: dict[str, Callable[..., Any]]) -> None:
        self._substitutes = substitutes
        self._done: dict[Callable[..., Any], Callable[..., Any]] = {}

    def __call__(self, func: Callable[..., Any]) -> Callable[..., Any]:
        done = self._done.get(func)
        if done is not None:
            return done
        copy, namespace = _copy_with_globals(func)
        self._done[func] = copy
        _point_globals(namespace, self._substitutes, self, compile_substitutes=False)
        return copy


@cache
def _backend(name: str) -> Backend:
    if name == "numba":
        return Backend(name, _Compiler())
    if name == "scipy":
        from ecdsim.dynamics import scipy_steppers

        stepping: dict[str, Callable[..., Any]] = {
            "start_stepper": scipy_steppers.start_stepper,
            "attempt": scipy_steppers.attempt,
        }
        return Backend(name, _Substituter(stepping))
    return Backend(name, lambda func: func)


def backend(name: str | None = None) -> Backend:
    """The kernel's entry points, compiled (``"numba"``) or plain (``"python"``), or
    plain with scipy's steppers (``"scipy"``: ``[analysis] integrator`` Radau, BDF,
    LSODA; :mod:`ecdsim.dynamics.scipy_steppers`).

    Without a name: compiled when numba is installed and not switched off
    (``ECDSIM_NUMBA=0``), else plain.
    """
    return _backend(resolve_name(name))


@cache
def substituted(
    func: Callable[..., Any], name: str, tag: str, substitutes: tuple[tuple[str, Any], ...]
) -> Any:
    """``func`` (a model's entry point, in a package of :data:`MODEL_PACKAGES`) with the
    kernel's hinge equations replaced by the model's, recursively, in the backend
    ``name``: compiled (``"numba"``), plain (``"python"``), or plain with scipy's steppers
    (``"scipy"``). ``substitutes`` pairs global names (``"derivatives"``, ``"jacobian"``,
    ``"event_value"``) with the model's functions; ``tag`` (``"wing"``) keeps its
    compiled code's cache entries apart from the hinge's."""
    replace: dict[str, Callable[..., Any]] = dict(substitutes)
    if name == "numba":
        return _Compiler(replace, tag)(func)
    if name == "scipy":
        from ecdsim.dynamics import scipy_steppers

        replace["start_stepper"] = _Substituter(dict(replace))(scipy_steppers.start_stepper)
        replace["attempt"] = scipy_steppers.attempt
    return _Substituter(replace)(func)


def resolve_name(name: str | None) -> str:
    """The backend's name: as given, or ``"numba"`` where available and not switched
    off, else ``"python"``."""
    if name is None:
        return "numba" if numba_requested() and _numba_available() else "python"
    if name not in ("numba", "python", "scipy"):
        raise ValueError(f"backend must be 'numba', 'python' or 'scipy', got {name!r}")
    return name


def _numba_available() -> bool:
    """numba imports (with ecdsim's set-up, :func:`ecdsim._numba.available`)."""
    return _numba.available()
