"""Array type aliases shared by the physics and solver layers."""

import math
from collections.abc import Sequence
from typing import TypeAlias, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray: TypeAlias = NDArray[np.float64]
BoolArray: TypeAlias = NDArray[np.bool_]
# A float or a float array: the argument and result type of the physics laws written once
# for both (and compiled by numba from the same source, ecdsim.dynamics.kernel).
Real: TypeAlias = float | FloatArray
_Item = TypeVar("_Item", bound=np.generic)

__all__ = [
    "ArrayLike",
    "BoolArray",
    "FloatArray",
    "Real",
    "all_true",
    "any_true",
    "as_float",
    "broadcast",
    "joint_shape",
    "one_case_rows",
    "one_case_views",
]


def as_float(value: object) -> FloatArray:
    """``value`` as a float64 array (typed, so that NumPy arithmetic stays checked)."""
    return np.asarray(value, dtype=np.float64)


def broadcast(value: NDArray[_Item], shape: tuple[int, ...]) -> NDArray[_Item]:
    """``np.broadcast_to(value, shape)``: a read-only view of ``value`` with ``shape``.

    The same view, built without NumPy's general machinery (about 2 us a call) where
    that is plain: ``value`` has the shape already, or is one number and ``shape`` one
    case. The per-case fields of a problem are broadcast dozens of times per solve, and
    a single deployment pays that fixed cost in full (issue 13, single cases).
    """
    if value.shape == shape:
        if not value.flags.writeable:
            return value  # already a read-only array of the shape (a problem's field)
        view = value.view()
    elif value.size == 1 and math.prod(shape) == 1:
        view = value.reshape(shape)
    else:
        return np.broadcast_to(value, shape)
    view.flags.writeable = False
    return view


def one_case_views(values: Sequence[FloatArray], shape: tuple[int, ...]) -> list[FloatArray]:
    """``[broadcast(v, shape) for v in values]`` for one case (``shape`` of size 1).

    Each value holds one number; they are read into one read-only float64 array and
    each is handed its own row, a read-only view of ``shape``: the same values, shape
    and dtype as :func:`broadcast` returns, for one NumPy call instead of one per value
    (a single deployment's problem has some 30 per-case fields; issue 13).
    """
    return one_case_rows([value.item() for value in values], shape)


def one_case_rows(numbers: Sequence[float], shape: tuple[int, ...]) -> list[FloatArray]:
    """:func:`one_case_views` of numbers already read off their arrays (``item()``)."""
    packed = np.array(numbers, dtype=np.float64)
    packed.flags.writeable = False
    rows = packed.reshape((len(numbers), *shape))
    if not shape:  # iterating would give NumPy scalars: index 0-d views instead
        return [rows[i, ...] for i in range(len(numbers))]
    return list(rows)  # the rows as views, iterated in C


def joint_shape(*shapes: tuple[int, ...]) -> tuple[int, ...]:
    """``np.broadcast_shapes(*shapes)``, at once where all are one shape or scalars ``()``."""
    distinct = set(shapes)
    distinct.discard(())
    if len(distinct) <= 1:
        return distinct.pop() if distinct else ()
    return np.broadcast_shapes(*shapes)


def any_true(mask: NDArray[np.bool_] | np.bool_) -> bool:
    """``bool(np.any(mask))``, read straight off the element when there is one.

    A reduction costs about 1 us (``np.any`` 2 us) whatever the size; a single
    deployment asks a dozen of these questions of one-element masks (issue 13, single
    cases), where ``item()`` answers in a few tens of nanoseconds.
    """
    if mask.size == 1:
        return bool(mask.item())
    return bool(mask.any())


def all_true(mask: NDArray[np.bool_] | np.bool_) -> bool:
    """``bool(np.all(mask))``, read straight off the element when there is one (see
    :func:`any_true`)."""
    if mask.size == 1:
        return bool(mask.item())
    return bool(mask.all())
