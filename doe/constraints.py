"""Targets, priors and constraints for calibration, all plain JSON-able data.

A linear constraint may be written as text ('friction_pw <= friction_pp',
'2*a + b >= 0.3'); it is parsed with the ast module into coefficients, never
evaluated, so user text cannot run code.
"""
from __future__ import annotations

import ast
import re
import math
from dataclasses import dataclass, field
from typing import Callable

from .factors import DoeError


@dataclass
class Target:
    """A measured bulk value the calibrated model should reproduce."""

    response: str
    value: float
    uncertainty: float          # one standard deviation, e.g. from replicate tests
    test: str = ""
    condition: str = ""

    def __post_init__(self):
        self.value, self.uncertainty = float(self.value), float(self.uncertainty)
        if not math.isfinite(self.value):
            raise DoeError(f"target {self.response}: value must be a finite number")
        if not (self.uncertainty > 0 and math.isfinite(self.uncertainty)):
            raise DoeError(f"target {self.response}: uncertainty must be a positive number")

    @classmethod
    def from_dict(cls, d: dict) -> "Target":
        try:
            return cls(str(d["response"]), d["value"], d["uncertainty"], str(d.get("test", "")),
                       str(d.get("condition", "")))
        except KeyError as exc:
            raise DoeError(f"target lacks {exc.args[0]!r}") from None

    def to_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass
class Prior:
    """A directly measured parameter (e.g. particle density by water displacement)."""

    parameter: str
    value: float
    uncertainty: float
    source: str = ""

    def __post_init__(self):
        self.value, self.uncertainty = float(self.value), float(self.uncertainty)
        if not (self.uncertainty > 0 and math.isfinite(self.uncertainty)):
            raise DoeError(f"prior on {self.parameter}: uncertainty must be a positive number")

    @classmethod
    def from_dict(cls, d: dict) -> "Prior":
        try:
            return cls(str(d["parameter"]), d["value"], d["uncertainty"], str(d.get("source", "")))
        except KeyError as exc:
            raise DoeError(f"prior lacks {exc.args[0]!r}") from None

    def to_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass
class LinearConstraint:
    """lower <= sum(coefficients[name] * value[name]) <= upper, natural units."""

    coefficients: dict[str, float]
    lower: float = -math.inf
    upper: float = math.inf
    name: str = ""

    def __post_init__(self):
        if not self.coefficients:
            raise DoeError(f"constraint {self.name!r} has no parameters")
        if not self.lower <= self.upper:
            raise DoeError(f"constraint {self.name!r}: lower bound exceeds upper bound")
        if not self.name:
            self.name = describe_linear(self.coefficients, self.lower, self.upper)

    def value(self, params: dict[str, float]) -> float:
        return sum(c * params[n] for n, c in self.coefficients.items())

    @property
    def parameters(self) -> list[str]:
        return list(self.coefficients)

    def to_dict(self) -> dict:
        return {"type": "linear", "name": self.name, "coefficients": dict(self.coefficients),
                "lower": None if math.isinf(self.lower) else self.lower,
                "upper": None if math.isinf(self.upper) else self.upper}


@dataclass
class NonlinearConstraint:
    """lower <= fun(parameters) <= upper, for relations a line cannot express."""

    fun: Callable[[dict[str, float]], float]
    lower: float = -math.inf
    upper: float = math.inf
    name: str = "nonlinear constraint"
    parameters: list[str] = field(default_factory=list)

    def value(self, params: dict[str, float]) -> float:
        return float(self.fun(params))

    def to_dict(self) -> dict:
        return {"type": "nonlinear", "name": self.name,
                "lower": None if math.isinf(self.lower) else self.lower,
                "upper": None if math.isinf(self.upper) else self.upper}


def describe_linear(coefs: dict[str, float], lower: float, upper: float) -> str:
    expr = " ".join(f"{'-' if c < 0 else '+'} {'' if abs(c) == 1 else f'{abs(c):g}*'}{n}"
                    for n, c in coefs.items()).lstrip("+ ")
    if math.isinf(lower):
        return f"{expr} <= {upper:g}"
    if math.isinf(upper):
        return f"{expr} >= {lower:g}"
    return f"{lower:g} <= {expr} <= {upper:g}"


def _linear(node) -> tuple[dict[str, float], float]:
    """Coefficients and constant of a linear expression tree."""
    if isinstance(node, ast.Expression):
        return _linear(node.body)
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
        return {}, float(node.value)
    if isinstance(node, ast.Name):
        return {node.id: 1.0}, 0.0
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        c, k = _linear(node.operand)
        s = -1.0 if isinstance(node.op, ast.USub) else 1.0
        return {n: s * v for n, v in c.items()}, s * k
    if isinstance(node, ast.BinOp):
        lc, lk = _linear(node.left)
        rc, rk = _linear(node.right)
        if isinstance(node.op, (ast.Add, ast.Sub)):
            s = 1.0 if isinstance(node.op, ast.Add) else -1.0
            out = dict(lc)
            for n, v in rc.items():
                out[n] = out.get(n, 0.0) + s * v
            return out, lk + s * rk
        if isinstance(node.op, ast.Mult) and (not lc or not rc):
            c, k, m = (rc, rk, lk) if not lc else (lc, lk, rk)
            return {n: m * v for n, v in c.items()}, m * k
        if isinstance(node.op, ast.Div) and not rc and rk != 0:
            return {n: v / rk for n, v in lc.items()}, lk / rk
    raise DoeError("constraint must be linear in the parameters (numbers, names, + - * /)")


# A linear constraint among a handful of factors needs a few terms; the parser recurses once per operator,
# so a 1,000-term expression exhausted Python's recursion limit (a 500 from the campaign API). Longer text
# is refused before it is parsed.
MAX_CONSTRAINT_TERMS = 64
MAX_CONSTRAINT_CHARS = 1000
_TERM = re.compile(r"[A-Za-z_][A-Za-z0-9_]*|\d+\.?\d*(?:[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?")
_OPERATOR = re.compile(r"[-+*/()]")


def check_constraint_size(text: str) -> None:
    """DoeError when ``text`` is longer than ``MAX_CONSTRAINT_CHARS`` or has more than ``MAX_CONSTRAINT_TERMS``
    names and numbers, or more operators and parentheses than that allows: it is then refused before the
    recursive parser sees it."""
    if len(text) > MAX_CONSTRAINT_CHARS:
        raise DoeError(f"constraint has {len(text)} characters, over the limit of {MAX_CONSTRAINT_CHARS}")
    terms = len(_TERM.findall(text))
    if terms > MAX_CONSTRAINT_TERMS:
        raise DoeError(f"constraint has {terms} terms, over the limit of {MAX_CONSTRAINT_TERMS}")
    operators = len(_OPERATOR.findall(text))
    if operators > 4 * MAX_CONSTRAINT_TERMS:
        raise DoeError(f"constraint has {operators} operators and parentheses, over the limit of "
                       f"{4 * MAX_CONSTRAINT_TERMS}")


def parse_constraint(text: str, name: str = "") -> LinearConstraint:
    """'friction_pw <= friction_pp' -> LinearConstraint({'friction_pw': 1, 'friction_pp': -1}, upper=0)."""
    check_constraint_size(text)
    for op in ("<=", ">="):
        if op in text:
            lhs, rhs = text.split(op, 1)
            break
    else:
        raise DoeError(f"constraint {text!r}: expected '<=' or '>='")
    try:
        lc, lk = _linear(ast.parse(lhs.strip(), mode="eval"))
        rc, rk = _linear(ast.parse(rhs.strip(), mode="eval"))
    except SyntaxError:
        raise DoeError(f"constraint {text!r} is not a valid expression") from None
    coefs = dict(lc)
    for n, v in rc.items():
        coefs[n] = coefs.get(n, 0.0) - v
    coefs = {n: v for n, v in coefs.items() if v != 0}
    bound = rk - lk
    if op == "<=":
        return LinearConstraint(coefs, upper=bound, name=name or text.strip())
    return LinearConstraint(coefs, lower=bound, name=name or text.strip())


def as_constraint(c):
    if isinstance(c, (LinearConstraint, NonlinearConstraint)):
        return c
    if isinstance(c, str):
        return parse_constraint(c)
    if isinstance(c, dict):
        if "expression" in c:
            return parse_constraint(c["expression"], c.get("name", ""))
        lo = c.get("lower")
        hi = c.get("upper")
        return LinearConstraint({k: float(v) for k, v in c["coefficients"].items()},
                                -math.inf if lo is None else float(lo), math.inf if hi is None else float(hi),
                                c.get("name", ""))
    raise DoeError(f"cannot read constraint {c!r}")
