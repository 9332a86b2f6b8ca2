"""Translate plain Python functions of floats into C: the damper FMU's physics.

The damper FMU needs no Python, yet its laws are ecdsim's own: they are written once,
as plain Python functions (the laws of :mod:`ecdsim.physics` that the dynamic kernel
compiles with numba, composed in :mod:`ecdsim.fmu.equations`),
and this module turns their source into C, which the system's compiler builds into the
FMU's shared library at export. Nothing is typed out twice.

The translator reads each function's syntax tree (:mod:`ast`) and accepts a small,
explicit subset of Python, refusing anything else with a :class:`TranslationError`
naming the function and the line:

* arguments annotated ``float`` or ``Real`` (:data:`ecdsim._types.Real`, a float or an
  array in Python, numba and NumPy; one C ``double``), ``int``, ``bool`` (C ``int``) or
  ``Sequence[float]`` (``const double *``, with its length passed as an ``int``); a
  return annotation ``float``, ``int``, ``bool`` or ``tuple[float, ...]`` (returned
  through output pointers);
* statements: assignment to a name (or ``a, b = f(...)`` from a tuple-returning
  function), augmented assignment, ``if``/``elif``/``else``, ``for i in range(...)``,
  ``while``, ``return``, ``pass`` and docstrings;
* expressions: float and int literals, names, arithmetic (``+ - * / **``, unary minus),
  comparisons, ``and``/``or``/``not`` in conditions, conditional expressions, indexing a
  sequence argument, module-level numeric constants, calls of other translatable
  functions (found through the function's globals, and translated too), of ``math``
  (``exp``, ``expm1``, ``log``, ``log1p``, ``sqrt``, ``copysign``, ``fabs``, ``isfinite``,
  ``isinf``, ``isnan``, ``floor``, ``ceil``, ``sin``, ``cos``, ``tan``, ``atan2``,
  ``hypot``, ``pow``, ``inf``, ``nan``, ``pi``, ``e``), of ``np.exp`` (C ``exp``: the
  array laws' exponential) and of ``abs``, ``min``, ``max`` (two arguments) and ``float``.

The C keeps Python's order of operations (every operation parenthesised), its ``**``
(C ``pow``, as CPython's float power), its ``min``/``max`` (the first argument unless
the second is strictly smaller/larger) and its true division. Literals are written in
hexadecimal, so they are the same doubles. Compiled without contraction of multiplies
and adds into fused operations (``-ffp-contract=off``), the C gives the same IEEE
doubles as CPython on the same machine; the functions of libm are the platform's, as
CPython's are. Where Python raises (a division by zero, an overflow in ``math.exp``),
C gives inf or NaN: the translated laws guard their divisions.
"""

from __future__ import annotations

import ast
import builtins
import inspect
import math
import textwrap
import typing
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["TranslationError", "c_literal", "translate"]

PREFIX = "ecd_"

_MATH_FUNCTIONS: dict[str, tuple[str, str]] = {
    # name: (C function, result type)
    "exp": ("exp", "double"),
    "expm1": ("expm1", "double"),
    "log": ("log", "double"),
    "log1p": ("log1p", "double"),
    "sqrt": ("sqrt", "double"),
    "copysign": ("copysign", "double"),
    "fabs": ("fabs", "double"),
    "sin": ("sin", "double"),
    "cos": ("cos", "double"),
    "tan": ("tan", "double"),
    "atan2": ("atan2", "double"),
    "hypot": ("hypot", "double"),
    "pow": ("pow", "double"),
    "isfinite": ("isfinite", "int"),
    "isinf": ("isinf", "int"),
    "isnan": ("isnan", "int"),
    "floor": ("(int)floor", "int"),
    "ceil": ("(int)ceil", "int"),
}
_MATH_CONSTANTS = {"inf": "INFINITY", "nan": "NAN"}
_BINARY = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/"}
_COMPARE = {
    ast.Lt: "<",
    ast.LtE: "<=",
    ast.Gt: ">",
    ast.GtE: ">=",
    ast.Eq: "==",
    ast.NotEq: "!=",
}
# Python's min/max of two numbers, as C: the first unless the second is strictly
# smaller/larger (so NaN and signed zeros come out as CPython's).
HELPERS = {
    "ecd_py_min": "static double ecd_py_min(double a, double b) { return (b < a) ? b : a; }",
    "ecd_py_max": "static double ecd_py_max(double a, double b) { return (b > a) ? b : a; }",
}


# Names a local variable or argument cannot take in C: its keywords, and what math.h
# and the helpers above define.
_C_WORDS = (
    "auto break case char const continue default do double else enum extern float for goto "
    "if inline int long register restrict return short signed sizeof static struct switch "
    "typedef union unsigned void volatile while INFINITY NAN abs fmin fmax"
)
RESERVED = frozenset(_C_WORDS.split()) | {c.split(")")[-1] for c, _ in _MATH_FUNCTIONS.values()}


class TranslationError(ValueError):
    """A function uses Python that the translator does not accept; says where."""


def c_literal(value: float) -> str:
    """A C double literal that is exactly ``value`` (hexadecimal; inf and NaN by name).

    >>> c_literal(0.5)
    '0x1.0000000000000p-1'
    >>> c_literal(-math.inf)
    '(-INFINITY)'
    """
    if math.isnan(value):
        return "NAN"
    if math.isinf(value):
        return "INFINITY" if value > 0 else "(-INFINITY)"
    text = float(value).hex()
    return f"({text})" if text.startswith("-") else text


@dataclass(frozen=True)
class _Signature:
    """A translated function's C signature."""

    c_name: str
    arguments: tuple[tuple[str, str], ...]  # (name, C type)
    result: str  # "double", "int" or "tuple"
    outputs: int  # number of results of a tuple-returning function


def _is_float(annotation: Any) -> bool:
    """``float``, or ecdsim's ``Real`` (a float or a float array: one double in C)."""
    from ecdsim._types import Real

    return annotation is float or annotation == Real


def _type_of(annotation: Any, where: str) -> str:
    if _is_float(annotation):
        return "double"
    if annotation is int or annotation is bool:
        return "int"
    origin = typing.get_origin(annotation)
    if origin is not None and origin.__name__ == "Sequence":
        (item,) = typing.get_args(annotation)
        if item is float:
            return "const double *"
    raise TranslationError(f"{where}: unsupported annotation {annotation!r}")


def _signature(function: Callable[..., Any]) -> _Signature:
    where = f"{function.__module__}.{function.__qualname__}"
    hints = typing.get_type_hints(function)
    names = list(inspect.signature(function).parameters)
    clashes = [name for name in names if name in RESERVED or name.startswith("ecd_")]
    if clashes:
        raise TranslationError(f"{where}: rename {', '.join(clashes)} (reserved in C)")
    missing = [name for name in [*names, "return"] if name not in hints]
    if missing:
        raise TranslationError(f"{where}: annotate {', '.join(missing)}")
    arguments = tuple((name, _type_of(hints[name], f"{where}({name})")) for name in names)
    result = hints["return"]
    if typing.get_origin(result) is tuple:
        items = typing.get_args(result)
        if not items or not all(_is_float(item) for item in items):
            raise TranslationError(f"{where}: a tuple result must be tuple[float, ...]")
        return _Signature(PREFIX + function.__name__, arguments, "tuple", len(items))
    return _Signature(PREFIX + function.__name__, arguments, _type_of(result, where), 0)


@dataclass
class _Function:
    """One function being translated: its scope and the C lines of its body."""

    function: Callable[..., Any]
    signature: _Signature
    callees: list[Callable[..., Any]]
    lines: list[str] = field(default_factory=list)
    local_types: dict[str, str] = field(default_factory=dict)
    helpers: set[str] = field(default_factory=set)

    @property
    def where(self) -> str:
        return f"{self.function.__module__}.{self.function.__qualname__}"

    def fail(self, node: ast.AST, message: str) -> TranslationError:
        line = getattr(node, "lineno", 0) + self.function.__code__.co_firstlineno - 1
        return TranslationError(f"{self.where} (line {line}): {message}")


class _Translator:
    """Translates one function's body; asks the collection for other functions' C names."""

    def __init__(self, unit: _Function, signatures: Callable[[Callable[..., Any]], _Signature]):
        self.unit = unit
        self.signatures = signatures
        self.arguments = dict(unit.signature.arguments)

    # Names and values ------------------------------------------------------------
    def _resolve(self, node: ast.expr) -> Any:
        """The object a global name or dotted attribute refers to (no side effects)."""
        parts: list[str] = []
        while isinstance(node, ast.Attribute):
            parts.append(node.attr)
            node = node.value
        if not isinstance(node, ast.Name):
            raise self.unit.fail(node, "only names and module attributes can be called")
        scope = self.unit.function.__globals__
        if node.id in scope:
            value = scope[node.id]
        elif hasattr(builtins, node.id):
            value = getattr(builtins, node.id)
        else:
            raise self.unit.fail(node, f"unknown name {node.id!r}")
        for attribute in reversed(parts):
            value = getattr(value, attribute)
        return value

    def _type(self, name: str, node: ast.AST) -> str:
        if name in self.arguments:
            return self.arguments[name]
        if name in self.unit.local_types:
            return self.unit.local_types[name]
        raise self.unit.fail(node, f"{name!r} is used before it is assigned")

    # Expressions -----------------------------------------------------------------
    def expression(self, node: ast.expr) -> tuple[str, str]:
        """(C text, C type) of an expression."""
        method = getattr(self, f"_{type(node).__name__}", None)
        if method is None:
            raise self.unit.fail(node, f"{type(node).__name__} is not translated")
        result: tuple[str, str] = method(node)
        return result

    def _number(self, value: object, node: ast.AST, what: str) -> tuple[str, str]:
        """(C literal, C type) of a Python number; ``what`` says what else it was."""
        if isinstance(value, bool):
            return ("1" if value else "0"), "int"
        if isinstance(value, int):
            return str(value), "int"
        if isinstance(value, float):
            return c_literal(value), "double"
        raise self.unit.fail(node, what)

    def _Constant(self, node: ast.Constant) -> tuple[str, str]:
        return self._number(node.value, node, f"constant {node.value!r} is not a number")

    def _Name(self, node: ast.Name) -> tuple[str, str]:
        if node.id in self.arguments or node.id in self.unit.local_types:
            return node.id, self._type(node.id, node)
        return self._global_value(node)

    def _Attribute(self, node: ast.Attribute) -> tuple[str, str]:
        is_math = isinstance(node.value, ast.Name) and self._resolve(node.value) is math
        if is_math and node.attr in _MATH_CONSTANTS:
            return _MATH_CONSTANTS[node.attr], "double"
        return self._global_value(node)

    def _global_value(self, node: ast.expr) -> tuple[str, str]:
        value = self._resolve(node)
        return self._number(value, node, "only numeric module constants can be read")

    def _BinOp(self, node: ast.BinOp) -> tuple[str, str]:
        left, left_type = self.expression(node.left)
        right, right_type = self.expression(node.right)
        if isinstance(node.op, ast.Pow):
            return f"pow((double)({left}), (double)({right}))", "double"
        if isinstance(node.op, ast.Div):  # true division, as Python's
            return f"((double)({left}) / (double)({right}))", "double"
        operator = _BINARY.get(type(node.op))
        if operator is None:
            raise self.unit.fail(node, f"operator {type(node.op).__name__} is not translated")
        kind = "int" if left_type == right_type == "int" else "double"
        return f"({left} {operator} {right})", kind

    def _UnaryOp(self, node: ast.UnaryOp) -> tuple[str, str]:
        operand, kind = self.expression(node.operand)
        if isinstance(node.op, ast.USub):
            return f"(-{operand})", kind
        if isinstance(node.op, ast.UAdd):
            return operand, kind
        if isinstance(node.op, ast.Not):
            return f"(!{operand})", "int"
        raise self.unit.fail(node, f"operator {type(node.op).__name__} is not translated")

    def _Compare(self, node: ast.Compare) -> tuple[str, str]:
        parts = []
        left, _ = self.expression(node.left)
        for op, comparator in zip(node.ops, node.comparators, strict=True):
            operator = _COMPARE.get(type(op))
            if operator is None:
                raise self.unit.fail(node, f"comparison {type(op).__name__} is not translated")
            simple = isinstance(comparator, ast.Name | ast.Constant | ast.Attribute)
            if not simple and len(node.ops) > 1:  # a chain would evaluate it twice
                raise self.unit.fail(node, "chain comparisons of names and constants only")
            right, _ = self.expression(comparator)
            parts.append(f"({left} {operator} {right})")
            left = right
        return "(" + " && ".join(parts) + ")", "int"

    def _BoolOp(self, node: ast.BoolOp) -> tuple[str, str]:
        operator = " && " if isinstance(node.op, ast.And) else " || "
        return "(" + operator.join(self.expression(v)[0] for v in node.values) + ")", "int"

    def _IfExp(self, node: ast.IfExp) -> tuple[str, str]:
        test, _ = self.expression(node.test)
        body, body_type = self.expression(node.body)
        other, other_type = self.expression(node.orelse)
        kind = "int" if body_type == other_type == "int" else "double"
        return f"({test} ? {body} : {other})", kind

    def _Subscript(self, node: ast.Subscript) -> tuple[str, str]:
        if not (isinstance(node.value, ast.Name) and node.value.id in self.arguments):
            raise self.unit.fail(node, "only sequence arguments can be indexed")
        if self.arguments[node.value.id] != "const double *":
            raise self.unit.fail(node, f"{node.value.id!r} is not a sequence")
        index, kind = self.expression(node.slice)
        if kind != "int":
            raise self.unit.fail(node, "an index must be an int")
        return f"{node.value.id}[{index}]", "double"

    def _Call(self, node: ast.Call) -> tuple[str, str]:
        if node.keywords:
            raise self.unit.fail(node, "keyword arguments are not translated")
        target = self._resolve(node.func)
        arguments = [self.expression(argument) for argument in node.args]
        texts = [text for text, _ in arguments]
        if target is abs:
            (kind,) = (k for _, k in arguments)
            return (
                (f"fabs({texts[0]})", "double")
                if kind == "double"
                else (
                    f"abs({texts[0]})",
                    "int",
                )
            )
        if target is min or target is max:
            if len(texts) != 2:
                raise self.unit.fail(node, "min and max take two arguments here")
            helper = "ecd_py_min" if target is min else "ecd_py_max"
            self.unit.helpers.add(helper)
            return f"{helper}((double)({texts[0]}), (double)({texts[1]}))", "double"
        if target is float:
            if len(node.args) == 1 and isinstance(node.args[0], ast.Constant):
                word = str(node.args[0].value).lower()
                if word in ("inf", "+inf", "infinity"):
                    return "INFINITY", "double"
                if word in ("-inf", "-infinity"):
                    return "(-INFINITY)", "double"
                if word == "nan":
                    return "NAN", "double"
            return f"((double)({texts[0]}))", "double"
        if target is np.exp:  # the array laws' exponential, one double at a time in C
            return f"exp({', '.join(texts)})", "double"
        if getattr(target, "__module__", None) == "math" and target.__name__ in _MATH_FUNCTIONS:
            c_function, kind = _MATH_FUNCTIONS[target.__name__]
            return f"{c_function}({', '.join(texts)})", kind
        if inspect.isfunction(target):
            signature = self.signatures(target)
            if signature.result == "tuple":
                raise self.unit.fail(node, "call a tuple-returning function as `a, b = f(...)`")
            self._check_arity(node, signature, arguments)
            return f"{signature.c_name}({', '.join(texts)})", signature.result
        raise self.unit.fail(node, f"cannot call {target!r}")

    def _check_arity(
        self, node: ast.AST, signature: _Signature, arguments: list[tuple[str, str]]
    ) -> None:
        if len(arguments) != len(signature.arguments):
            raise self.unit.fail(
                node, f"{signature.c_name} takes {len(signature.arguments)} arguments"
            )
        for (name, expected), (_, given) in zip(signature.arguments, arguments, strict=True):
            if (expected == "const double *") != (given == "const double *"):
                raise self.unit.fail(node, f"argument {name!r}: a sequence is passed as is")

    # Statements ------------------------------------------------------------------
    def body(self, statements: Sequence[ast.stmt], depth: int) -> None:
        for statement in statements:
            self.statement(statement, depth)

    def emit(self, depth: int, text: str) -> None:
        self.unit.lines.append("    " * depth + text)

    def statement(self, node: ast.stmt, depth: int) -> None:
        method = getattr(self, f"_stmt_{type(node).__name__}", None)
        if method is None:
            raise self.unit.fail(node, f"{type(node).__name__} statements are not translated")
        method(node, depth)

    def _declare(self, name: str, kind: str, node: ast.AST) -> None:
        if name in RESERVED or name.startswith("ecd_"):
            raise self.unit.fail(node, f"{name!r} is a reserved word in C: rename it")
        if name in self.arguments:
            raise self.unit.fail(node, f"argument {name!r} is assigned: use a new name")
        known = self.unit.local_types.get(name)
        if known is None:
            self.unit.local_types[name] = kind
        elif known == "int" and kind == "double":
            raise self.unit.fail(node, f"{name!r} is an int and is assigned a float")

    def _stmt_Expr(self, node: ast.Expr, depth: int) -> None:
        if isinstance(node.value, ast.Constant) and isinstance(node.value.value, str):
            return  # a docstring
        raise self.unit.fail(node, "an expression statement does nothing here")

    def _stmt_Pass(self, node: ast.Pass, depth: int) -> None:
        return

    def _stmt_Assign(self, node: ast.Assign, depth: int) -> None:
        if len(node.targets) != 1:
            raise self.unit.fail(node, "assign one target at a time")
        target = node.targets[0]
        if isinstance(target, ast.Name):
            text, kind = self.expression(node.value)
            self._declare(target.id, kind, node)
            self.emit(depth, f"{target.id} = {text};")
            return
        if isinstance(target, ast.Tuple) and isinstance(node.value, ast.Call):
            names = []
            for element in target.elts:
                if not isinstance(element, ast.Name):
                    raise self.unit.fail(node, "unpack into names")
                names.append(element.id)
            function = self._resolve(node.value.func)
            if not inspect.isfunction(function):
                raise self.unit.fail(node, "unpack the result of a translatable function")
            signature = self.signatures(function)
            if signature.result != "tuple" or signature.outputs != len(names):
                raise self.unit.fail(node, f"{signature.c_name} does not return {len(names)}")
            arguments = [self.expression(argument) for argument in node.value.args]
            self._check_arity(node, signature, arguments)
            for name in names:
                self._declare(name, "double", node)
            pointers = ", ".join(f"&{name}" for name in names)
            texts = ", ".join(text for text, _ in arguments)
            self.emit(depth, f"{signature.c_name}({texts}, {pointers});")
            return
        raise self.unit.fail(node, "assign to a name, or unpack a call into names")

    def _stmt_AnnAssign(self, node: ast.AnnAssign, depth: int) -> None:
        if not isinstance(node.target, ast.Name) or node.value is None:
            raise self.unit.fail(node, "annotated assignments need a name and a value")
        self._stmt_Assign(ast.Assign(targets=[node.target], value=node.value), depth)

    def _stmt_AugAssign(self, node: ast.AugAssign, depth: int) -> None:
        if not isinstance(node.target, ast.Name):
            raise self.unit.fail(node, "augment a name")
        value = ast.BinOp(left=ast.Name(id=node.target.id), op=node.op, right=node.value)
        ast.copy_location(value, node)
        self._stmt_Assign(ast.Assign(targets=[node.target], value=value), depth)

    def _stmt_If(self, node: ast.If, depth: int) -> None:
        test, _ = self.expression(node.test)
        self.emit(depth, f"if ({test}) {{")
        self.body(node.body, depth + 1)
        if node.orelse:
            self.emit(depth, "} else {")
            self.body(node.orelse, depth + 1)
        self.emit(depth, "}")

    def _stmt_While(self, node: ast.While, depth: int) -> None:
        if node.orelse:
            raise self.unit.fail(node, "while ... else is not translated")
        test, _ = self.expression(node.test)
        self.emit(depth, f"while ({test}) {{")
        self.body(node.body, depth + 1)
        self.emit(depth, "}")

    def _stmt_For(self, node: ast.For, depth: int) -> None:
        call = node.iter
        if (
            node.orelse
            or not isinstance(node.target, ast.Name)
            or not isinstance(call, ast.Call)
            or self._resolve(call.func) is not range
        ):
            raise self.unit.fail(node, "loop as `for name in range(...)`")
        arguments = [self.expression(argument) for argument in call.args]
        if any(kind != "int" for _, kind in arguments) or not 1 <= len(arguments) <= 3:
            raise self.unit.fail(node, "range takes one to three ints")
        texts = [text for text, _ in arguments]
        start, stop = ("0", texts[0]) if len(texts) == 1 else (texts[0], texts[1])
        step = 1
        if len(call.args) == 3:
            literal = call.args[2]
            negative = isinstance(literal, ast.UnaryOp) and isinstance(literal.op, ast.USub)
            value = literal.operand if isinstance(literal, ast.UnaryOp) else literal
            if not (isinstance(value, ast.Constant) and type(value.value) is int):
                raise self.unit.fail(node, "a range step must be an int literal")
            step = -value.value if negative else value.value
            if step == 0:
                raise self.unit.fail(node, "a range step cannot be 0")
        name = node.target.id
        for inner in ast.walk(ast.Module(body=node.body, type_ignores=[])):
            targets = getattr(inner, "targets", None) or [getattr(inner, "target", None)]
            if any(isinstance(t, ast.Name) and t.id == name for t in targets):
                raise self.unit.fail(inner, f"the loop variable {name!r} is assigned")
        self._declare(name, "int", node)
        compare = "<" if step > 0 else ">"
        self.emit(
            depth,
            f"for ({name} = {start}; {name} {compare} {stop}; {name} += {step}) {{",
        )
        self.body(node.body, depth + 1)
        self.emit(depth, "}")

    def _stmt_Return(self, node: ast.Return, depth: int) -> None:
        signature = self.unit.signature
        if node.value is None:
            raise self.unit.fail(node, "return a value")
        if signature.result == "tuple":
            if not isinstance(node.value, ast.Tuple) or len(node.value.elts) != signature.outputs:
                raise self.unit.fail(node, f"return {signature.outputs} values")
            for i, element in enumerate(node.value.elts):
                text, _ = self.expression(element)
                self.emit(depth, f"*ecd_out{i} = {text};")
            self.emit(depth, "return;")
            return
        text, _ = self.expression(node.value)
        self.emit(depth, f"return {text};")


class _Collection:
    """The functions to translate, found from the roots through their calls."""

    def __init__(self) -> None:
        self.signatures: dict[Callable[..., Any], _Signature] = {}
        self.order: list[Callable[..., Any]] = []
        self.pending: list[Callable[..., Any]] = []
        self.names: dict[str, Callable[..., Any]] = {}

    def signature(self, function: Callable[..., Any]) -> _Signature:
        if function not in self.signatures:
            signature = _signature(function)
            other = self.names.get(signature.c_name)
            if other is not None and other is not function:
                raise TranslationError(
                    f"{function.__module__}.{function.__qualname__} and "
                    f"{other.__module__}.{other.__qualname__} share the name "
                    f"{function.__name__!r}"
                )
            self.names[signature.c_name] = function
            self.signatures[function] = signature
            self.order.append(function)
            self.pending.append(function)
        return self.signatures[function]


def _parse(function: Callable[..., Any]) -> ast.FunctionDef:
    source = textwrap.dedent(inspect.getsource(function))
    tree = ast.parse(source)
    node = tree.body[0]
    if not isinstance(node, ast.FunctionDef):
        raise TranslationError(f"{function.__qualname__} is not a plain function")
    if node.decorator_list:
        raise TranslationError(f"{function.__qualname__}: decorated functions are not translated")
    return node


def _prototype(signature: _Signature) -> str:
    arguments = [f"{kind} {name}" for name, kind in signature.arguments]
    if signature.result == "tuple":
        arguments += [f"double *ecd_out{i}" for i in range(signature.outputs)]
        result = "void"
    else:
        result = signature.result
    return f"static {result} {signature.c_name}({', '.join(arguments) or 'void'})"


def _summary(function: Callable[..., Any]) -> str:
    doc = inspect.getdoc(function) or ""
    first = doc.strip().splitlines()[0] if doc.strip() else ""
    return first.replace("*/", "* /")


def translate(roots: Sequence[Callable[..., Any]]) -> str:
    """The C source of ``roots`` and every function they call, as static functions.

    Each C function is ``ecd_`` + the Python name, preceded by a comment naming the
    Python function it was translated from. Raises :class:`TranslationError` for Python
    outside the accepted subset (module docstring).
    """
    collection = _Collection()
    for root in roots:
        collection.signature(root)
    bodies: dict[Callable[..., Any], _Function] = {}
    while collection.pending:
        function = collection.pending.pop(0)
        signature = collection.signatures[function]
        unit = _Function(function, signature, callees=[])
        translator = _Translator(unit, collection.signature)
        node = _parse(function)
        translator.body(node.body, 1)
        last = node.body[-1] if node.body else None
        if not isinstance(last, ast.Return):
            # Every path of a translated function returns; C needs a last statement.
            unit.lines.append("    /* not reached: every path above returns */")
            unit.lines.append("    " + ("return;" if signature.result == "tuple" else "return 0;"))
        bodies[function] = unit
    used = set().union(*(unit.helpers for unit in bodies.values()))
    out = [HELPERS[name] for name in sorted(used)]
    out += [_prototype(collection.signatures[f]) + ";" for f in collection.order]
    for function in collection.order:
        unit = bodies[function]
        out.append("")
        out.append(f"/* {function.__module__}.{function.__qualname__}: {_summary(function)} */")
        out.append(_prototype(unit.signature) + " {")
        for name, kind in unit.local_types.items():
            out.append(f"    {kind} {name};")
        out += unit.lines
        out.append("}")
    return "\n".join(out) + "\n"
