"""Parametric descriptions: named design parameters and the expressions that use them.

A description may name its design parameters in a ``[parameters]`` table, each a number or an
expression of the others (``base_radius_m = 1.0``, ``leg_m = "norm(top_m - base_m)"``; a table
``{ value = 1.0, min = 0.5, max = 2.0 }`` gives bounds; each is evaluated after those it uses,
whatever the file's order, and a cycle is refused by name), and any numeric field may then be
an expression string (``point_m = "rotz(-half_angle_deg * deg) @ [base_radius_m, 0,
0]"``). Expressions are evaluated here, before validation, by walking Python's own parse tree
of the text (:func:`ast.parse`) with a closed set of nodes: numbers, the parameters' names,
``+ - * / ** @``, unary signs, parentheses, ``[a, b, c]`` vectors, ``v[0]`` (an entry, by a whole
number) and the calls below; no attribute, other subscript, keyword, comprehension or other
name is accepted (no Python ``eval``).

Grammar (``docs/mechanism_format.md``, "Parameters")::

    expr   := number | name | expr op expr | -expr | +expr | (expr) | [expr, ...] | f(expr, ...)
              | expr[k] (an entry of a vector, k a whole number)
    op     := + - * / ** @
    name   := a parameter | pi | deg (pi / 180)
    f      := sqrt abs exp log sin cos tan asin acos atan atan2 sind cosd tand hypot min max
              norm unit dot cross rotx roty rotz (radians) rotxd rotyd rotzd (degrees)

Vectors are 3-vectors or plain lists; ``rotz(a) @ v`` turns ``v`` about z by ``a`` [rad]. A
result must be finite; a field that expects a number takes a number, a field that expects a
list takes a list of the right length (the validation that follows says so, naming the key).
"""

from __future__ import annotations

import ast
import functools
import math
import re
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from ...errors import ParameterError
from ...spatial import cross

__all__ = ["evaluate", "resolve_parameters", "parameter_values", "parameter_bounds", "FUNCTIONS", "MAX_LENGTH"]

#: the longest expression text taken
MAX_LENGTH = 2000
#: the most nodes of one expression's parse tree
_MAX_NODES = 400
#: a parameter name: a letter, then letters, digits and underscores, ending in a unit suffix or not
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,63}$")


def _rot(axis: int, a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R = np.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def _vec(v: Any, name: str, n: int | None = None) -> np.ndarray:
    a = np.asarray(v, dtype=float)
    if a.ndim != 1 or (n is not None and a.shape[0] != n):
        raise ValueError(f"{name}: expects a vector{'' if n is None else f' of {n} numbers'}")
    return a


def _unit(v: Any) -> np.ndarray:
    a = _vec(v, "unit")
    n = float(np.linalg.norm(a))
    if not n > 0:
        raise ValueError("unit: of a zero vector")
    return a / n


def _scalar(f: Callable[..., float]) -> Callable[..., float]:
    def g(*args: Any) -> float:
        for a in args:
            if np.ndim(a) != 0:
                raise ValueError(f"{f.__name__}: expects numbers")
        return float(f(*(float(a) for a in args)))

    g.__name__ = f.__name__
    return g


#: the functions an expression may call
FUNCTIONS: dict[str, Callable[..., Any]] = {
    "sqrt": _scalar(math.sqrt), "abs": lambda a: np.abs(a) if np.ndim(a) else abs(float(a)),
    "exp": _scalar(math.exp), "log": _scalar(math.log),
    "sin": _scalar(math.sin), "cos": _scalar(math.cos), "tan": _scalar(math.tan),
    "asin": _scalar(math.asin), "acos": _scalar(math.acos), "atan": _scalar(math.atan),
    "atan2": _scalar(math.atan2), "hypot": _scalar(math.hypot),
    "sind": _scalar(lambda a: math.sin(math.radians(a))), "cosd": _scalar(lambda a: math.cos(math.radians(a))),
    "tand": _scalar(lambda a: math.tan(math.radians(a))),
    "min": _scalar(min), "max": _scalar(max),
    "norm": lambda v: float(np.linalg.norm(_vec(v, "norm"))), "unit": _unit,
    "dot": lambda a, b: float(np.dot(_vec(a, "dot"), _vec(b, "dot"))),
    "cross": lambda a, b: cross(_vec(a, "cross", 3), _vec(b, "cross", 3)),
    "rotx": lambda a: _rot(0, float(a)), "roty": lambda a: _rot(1, float(a)), "rotz": lambda a: _rot(2, float(a)),
    "rotxd": lambda a: _rot(0, math.radians(float(a))), "rotyd": lambda a: _rot(1, math.radians(float(a))),
    "rotzd": lambda a: _rot(2, math.radians(float(a))),
}
_CONSTANTS = {"pi": math.pi, "deg": math.pi / 180.0}
_BINARY: dict[type, Callable[[Any, Any], Any]] = {
    ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b, ast.Mult: lambda a, b: a * b,
    ast.Div: lambda a, b: a / b, ast.Pow: lambda a, b: a ** b, ast.MatMult: lambda a, b: a @ b,
}


def _eval(node: ast.AST, names: Mapping[str, Any]) -> Any:
    if isinstance(node, ast.Expression):
        return _eval(node.body, names)
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
        return float(node.value)
    if isinstance(node, ast.Name):
        if node.id in names:
            v = names[node.id]
            return np.asarray(v, dtype=float) if isinstance(v, (list, tuple, np.ndarray)) else v
        if node.id in _CONSTANTS:
            return _CONSTANTS[node.id]
        raise ValueError(f"unknown name {node.id!r} (the parameters are: {', '.join(names) or 'none'})")
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        v = _eval(node.operand, names)
        return -v if isinstance(node.op, ast.USub) else +v
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        a, b = _eval(node.left, names), _eval(node.right, names)
        if isinstance(node.op, ast.MatMult) and (np.ndim(a) == 0 or np.ndim(b) == 0):
            raise ValueError("@ multiplies a matrix and a vector")
        if isinstance(node.op, ast.Pow) and (np.ndim(a) or np.ndim(b)):
            raise ValueError("** takes numbers")
        if isinstance(node.op, ast.Div) and np.ndim(b) == 0 and float(b) == 0.0:
            raise ValueError("division by zero")
        with np.errstate(all="raise"):
            try:
                out = _BINARY[type(node.op)](a, b)
            except (FloatingPointError, OverflowError, ZeroDivisionError):
                raise ValueError("the value overflows") from None
        if np.iscomplexobj(out):  # a negative number to a fractional power
            raise ValueError("the value is not a real number (a negative number to a fractional power)")
        return out
    if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant) \
            and isinstance(node.slice.value, int) and not isinstance(node.slice.value, bool):
        v = _eval(node.value, names)
        k = node.slice.value
        if np.ndim(v) != 1 or not 0 <= k < len(v):
            raise ValueError(f"[{k}]: takes an entry of a vector (0 to its length - 1)")
        return float(v[k])
    if isinstance(node, ast.List):
        items = [_eval(e, names) for e in node.elts]
        if any(np.ndim(v) for v in items):
            raise ValueError("a vector's entries are numbers")
        return np.array(items, dtype=float)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and not node.keywords:
        f = FUNCTIONS.get(node.func.id)
        if f is None:
            raise ValueError(f"unknown function {node.func.id!r} (known: {', '.join(sorted(FUNCTIONS))})")
        args = [_eval(a, names) for a in node.args]
        try:
            out = f(*args)
            if np.iscomplexobj(out):
                raise ValueError(f"{node.func.id}: the value is not a real number")
            return out
        except TypeError:
            raise ValueError(f"{node.func.id}: wrong number of arguments") from None
        except (OverflowError, ZeroDivisionError):
            raise ValueError(f"{node.func.id}: the value overflows") from None
    what = type(node).__name__
    raise ValueError(f"{what!r} is not part of the expression grammar (numbers, parameters, + - * / ** @, "
                     "vectors [..], the listed functions)")


def evaluate(text: str, names: Mapping[str, Any], where: str = "expression") -> float | list[float]:
    """The value of the expression ``text`` over the parameters ``names`` (module docstring):
    a float, or a list of floats (a vector) or of lists (a matrix). Raises
    :class:`~pkmdyn.errors.ParameterError` naming ``where`` and what is wrong."""
    if not isinstance(text, str):
        raise ParameterError(f"{where}: expected an expression (text), got {type(text).__name__}")
    if len(text) > MAX_LENGTH:
        raise ParameterError(f"{where}: the expression is longer than {MAX_LENGTH} characters")
    tree, error, nodes, _ = _parsed(text)
    if error is not None:
        raise ParameterError(f"{where}: {text!r} is not an expression ({error})") from None
    if nodes > _MAX_NODES or tree is None:
        raise ParameterError(f"{where}: the expression has more than {_MAX_NODES} parts")
    try:
        with np.errstate(all="raise"):
            v = _eval(tree, names)
    except (ValueError, FloatingPointError, ArithmeticError) as exc:
        raise ParameterError(f"{where}: {text!r}: {exc}") from None
    a = np.asarray(v, dtype=float)
    if not np.all(np.isfinite(a)):
        raise ParameterError(f"{where}: {text!r} is not finite")
    return a.tolist() if a.ndim else float(a)


def parameter_values(raw: Mapping[str, Any], label: str) -> dict[str, Any]:
    """The ``[parameters]`` of a description (a number, an expression, or a table ``{ value,
    min, max }`` whose value must lie within its bounds), each evaluated after the parameters
    it uses, whatever their order in the file; returned in the file's order. A parameter that
    uses itself or one of a cycle is refused. Errors name the parameter."""
    table = raw.get("parameters", {})
    if not isinstance(table, dict):
        raise ParameterError(f"{label}: [parameters]: expected a table of named values")
    for name in table:
        if not _NAME.match(str(name)) or name in _CONSTANTS or name in FUNCTIONS:
            raise ParameterError(f"{label}: [parameters] {name}: not a usable parameter name (a letter, then "
                                 "letters, digits, underscores; not a function or constant of the grammar)")
    read = {str(k): _names_used(v.get("value") if isinstance(v, dict) else v) for k, v in table.items()}
    known = set(map(str, table))
    for name, names in read.items():
        for other in sorted(names - known - set(_CONSTANTS) - set(FUNCTIONS)):
            raise ParameterError(f"{label}: [parameters] {name}: unknown name {other!r} (the parameters are: "
                                 f"{', '.join(map(str, table))})")
    uses = {k: v & known for k, v in read.items()}
    done: dict[str, Any] = {}
    for name in _dependency_order(list(map(str, table)), uses, label):
        spec = table[name]
        where = f"{label}: [parameters] {name}"
        lo = hi = None
        if isinstance(spec, dict):
            unknown = set(spec) - {"value", "min", "max"}
            if unknown or "value" not in spec:
                raise ParameterError(f"{where}: a table takes value, min and max (value required)")
            lo, hi, spec = spec.get("min"), spec.get("max"), spec["value"]
        v = _value(spec, done, where)
        for bound, ok, word in ((lo, lambda x, b: x >= b, "below its min"), (hi, lambda x, b: x <= b, "above its max")):
            if bound is None:
                continue
            if isinstance(bound, bool) or not isinstance(bound, (int, float)) or not math.isfinite(bound):
                raise ParameterError(f"{where}: min and max must be finite numbers")
            if isinstance(v, list) or not ok(v, bound):
                raise ParameterError(f"{where}: {v} is {word} {bound:g}")
        done[name] = v
    return {str(k): done[str(k)] for k in table}


def parameter_bounds(raw: Mapping[str, Any]) -> dict[str, tuple[float | None, float | None]]:
    """The bounds ``(min, max)`` (either None where absent) of the bounded parameters of a
    description's ``[parameters]`` (``{ value, min, max }``), in the file's order; after
    :func:`parameter_values` has checked them."""
    table = raw.get("parameters", {})
    if not isinstance(table, dict):
        return {}
    return {str(k): (None if v.get("min") is None else float(v["min"]), None if v.get("max") is None else float(v["max"]))
            for k, v in table.items() if isinstance(v, dict) and ("min" in v or "max" in v)}


def _names_used(spec: Any) -> set[str]:
    """The names that a parameter's value (a number, an expression or a list of them) reads;
    an expression that does not parse reads none here (:func:`evaluate` reports it)."""
    if isinstance(spec, list):
        return set().union(*(_names_used(v) for v in spec))
    if not isinstance(spec, str) or len(spec) > MAX_LENGTH:
        return set()
    return set(_parsed(spec)[3])


@functools.lru_cache(maxsize=512)
def _parsed(text: str) -> tuple[ast.Expression | None, str | None, int, frozenset[str]]:
    """The parse tree of an expression's ``text`` (stripped; None where it does not parse or
    has more than :data:`_MAX_NODES` parts), the syntax error's message (None where it parses),
    its number of parts and the names it reads. Cached by text (at most :data:`MAX_LENGTH`
    characters): a sweep evaluates the same texts with other parameter values for every
    design, and :func:`_eval` only reads the tree, so a value is the same to the last bit."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        return None, str(exc.msg), 0, frozenset()
    nodes = list(ast.walk(tree))
    names = frozenset(n.id for n in nodes if isinstance(n, ast.Name))
    return (tree if len(nodes) <= _MAX_NODES else None), None, len(nodes), names


def _dependency_order(names: list[str], uses: Mapping[str, set[str]], label: str) -> list[str]:
    """``names`` ordered so that each comes after the parameters it uses (a depth-first
    topological sort from each name in the file's order). A parameter that uses
    itself, or a cycle, is refused, the cycle named in its order (``a_m -> b_m -> a_m``)."""
    order: list[str] = []
    state: dict[str, int] = {}  # 1: on the path being followed, 2: placed
    for root in names:
        if state.get(root):
            continue
        path = [root]
        state[root] = 1
        pending = [iter(sorted(uses[root], key=names.index))]
        while path:
            nxt = next(pending[-1], None)
            if nxt is None:  # every parameter it uses is placed: place it
                state[path[-1]] = 2
                order.append(path.pop())
                pending.pop()
            elif state.get(nxt) == 1:
                where = f"{label}: [parameters] {nxt}"
                if nxt == path[-1]:
                    raise ParameterError(f"{where}: uses itself")
                cycle = path[path.index(nxt):] + [nxt]
                raise ParameterError(f"{where}: a cycle between parameters: {' -> '.join(cycle)}")
            elif not state.get(nxt):
                state[nxt] = 1
                path.append(nxt)
                pending.append(iter(sorted(uses[nxt], key=names.index)))
    return order


def _value(spec: Any, names: Mapping[str, Any], where: str) -> Any:
    if isinstance(spec, bool):
        raise ParameterError(f"{where}: expected a number or an expression, got {spec!r}")
    if isinstance(spec, (int, float)):
        if not math.isfinite(spec):
            raise ParameterError(f"{where}: {spec} is not finite")
        return float(spec)
    if isinstance(spec, str):
        return evaluate(spec, names, where)
    if isinstance(spec, list):
        return [_value(s, names, f"{where}[{i}]") for i, s in enumerate(spec)]
    raise ParameterError(f"{where}: expected a number, an expression or a list, got {type(spec).__name__}")


#: keys whose values are text (names, types, sequences), never expressions
_TEXT_KEYS = {"name", "type", "parent", "child", "body", "joint", "kind", "euler_sequence", "source", "cut_joints",
              "bodies", "position", "suffixes", "load", "beam_axis", "distribution", "reactions"}


def resolve_parameters(raw: dict[str, Any], label: str) -> tuple[dict[str, Any], dict[str, Any]]:
    """The description ``raw`` with every expression evaluated (a copy; ``[parameters]`` left
    out), and the parameters' values (their bounds: :func:`parameter_bounds` of ``raw``). Only
    text in numeric fields is an expression: a string under a key that names a body, joint,
    type, sequence or other text is left as it is."""
    if not isinstance(raw, dict) or "parameters" not in raw:
        return raw, {}
    names = parameter_values(raw, label)

    def walk(v: Any, key: str, where: str) -> Any:
        if isinstance(v, dict):
            return {k: walk(x, k if k not in ("offset", "amplitude") else "offset", f"{where} {k}") for k, x in v.items()}
        if isinstance(v, list):
            return [walk(x, key, f"{where}[{i}]") for i, x in enumerate(v)]
        if isinstance(v, str) and key not in _TEXT_KEYS:
            return evaluate(v, names, f"{label}: {where}")
        return v

    out = {k: walk(v, k, f"[{k}]") for k, v in raw.items() if k != "parameters"}
    return out, names
