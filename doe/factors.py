"""Design factors: natural <-> coded units.

Coded units put the low level at -1 and the high level at +1 so that effects of
factors measured in kg/m3 and in dimensionless friction are comparable. A factor
spanning decades (stiffness, say) may be coded on a log10 scale, which makes the
centre the geometric mean of its levels.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

# Design-Expert skips I, which denotes the identity in alias algebra.
LETTERS = "ABCDEFGHJKLMNOPQRSTUVWXYZ"
_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_.]*$")


class DoeError(ValueError):
    """Bad input to a doe/ routine; the message names what is wrong."""


@dataclass(frozen=True)
class Factor:
    """One continuous design factor; `low`/`high` are in natural (user) units."""

    name: str
    low: float
    high: float
    unit: str = ""
    log: bool = False
    letter: str = field(default="", compare=False)

    def __post_init__(self):
        if not _NAME_RE.match(self.name or ""):
            raise DoeError(f"factor name {self.name!r} must start with a letter and use letters, digits, _ or .")
        low, high = float(self.low), float(self.high)
        if not (math.isfinite(low) and math.isfinite(high)):
            raise DoeError(f"factor {self.name}: levels must be finite numbers")
        if not low < high:
            raise DoeError(f"factor {self.name}: low level {low:g} must be below high level {high:g}")
        if self.log and low <= 0:
            raise DoeError(f"factor {self.name}: a log-scale factor needs positive levels")
        object.__setattr__(self, "low", low)
        object.__setattr__(self, "high", high)

    # transformed scale: x itself, or log10(x) for log factors
    def _t(self, x):
        return np.log10(x) if self.log else np.asarray(x, dtype=float)

    def _t_inv(self, t):
        return 10.0 ** t if self.log else t

    @property
    def centre_t(self) -> float:
        return float((self._t(self.low) + self._t(self.high)) / 2.0)

    @property
    def half_range_t(self) -> float:
        return float((self._t(self.high) - self._t(self.low)) / 2.0)

    @property
    def centre(self) -> float:
        """Natural value at coded 0 (geometric mean for log factors)."""
        return float(self._t_inv(self.centre_t))

    @property
    def symbol(self) -> str:
        """Variable name used in natural-unit regression equations."""
        return f"log10({self.name})" if self.log else self.name

    def to_coded(self, natural):
        natural = np.asarray(natural, dtype=float)
        if self.log and np.any(natural <= 0):
            raise DoeError(f"factor {self.name}: log-scale values must be positive")
        return (self._t(natural) - self.centre_t) / self.half_range_t

    def to_natural(self, coded):
        c = np.asarray(coded, dtype=float)
        x = self._t_inv(self.centre_t + c * self.half_range_t)
        # exact levels at the design points, free of round-off (0.05, not 0.05000000000000002)
        x = np.where(c == -1.0, self.low, np.where(c == 1.0, self.high, x))
        return x if x.ndim else float(x)

    def with_letter(self, letter: str) -> "Factor":
        return Factor(self.name, self.low, self.high, self.unit, self.log, letter)

    def with_levels(self, low: float, high: float) -> "Factor":
        return Factor(self.name, low, high, self.unit, self.log, self.letter)

    def to_dict(self) -> dict:
        return {"name": self.name, "letter": self.letter, "low": self.low, "high": self.high,
                "unit": self.unit, "log": self.log}

    @classmethod
    def from_dict(cls, d: dict) -> "Factor":
        try:
            return cls(str(d["name"]), float(d["low"]), float(d["high"]), str(d.get("unit", "")),
                       bool(d.get("log", False)), str(d.get("letter", "")))
        except KeyError as exc:
            raise DoeError(f"factor definition lacks {exc.args[0]!r}") from None
        except (TypeError, ValueError) as exc:
            if isinstance(exc, DoeError):
                raise
            raise DoeError(f"factor definition {d!r}: {exc}") from None


def as_factors(factors) -> tuple[Factor, ...]:
    """Accept Factor objects, dicts or (name, low, high[, unit]) tuples; assign letters A, B, ..."""
    out = []
    for f in factors:
        if isinstance(f, Factor):
            pass
        elif isinstance(f, dict):
            f = Factor.from_dict(f)
        else:
            f = Factor(*f)
        out.append(f)
    if not out:
        raise DoeError("at least one factor is needed")
    if len(out) > len(LETTERS):
        raise DoeError(f"at most {len(LETTERS)} factors are supported")
    names = [f.name for f in out]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise DoeError(f"duplicate factor names: {sorted(dup)}")
    return tuple(f.with_letter(LETTERS[i]) for i, f in enumerate(out))


def parse_factor(text: str) -> Factor:
    """Parse 'name:low:high[:unit][:log]' as typed on the command line."""
    parts = text.split(":")
    if len(parts) < 3:
        raise DoeError(f"factor {text!r}: expected name:low:high[:unit][:log]")
    log = False
    if len(parts) >= 4 and parts[-1].strip().lower() == "log":
        log = True
        parts = parts[:-1]
    if len(parts) > 4:
        raise DoeError(f"factor {text!r}: expected name:low:high[:unit][:log]")
    name, low, high = parts[0].strip(), parts[1], parts[2]
    unit = parts[3].strip() if len(parts) == 4 else ""
    try:
        low_v, high_v = float(low), float(high)
    except ValueError:
        raise DoeError(f"factor {text!r}: low and high must be numbers") from None
    return Factor(name, low_v, high_v, unit, log)


def coded_matrix(factors, natural_rows, row_label: str = "run") -> np.ndarray:
    """Rows of natural values (dicts keyed by factor name) -> n x k coded array."""
    out = np.empty((len(natural_rows), len(factors)))
    for i, row in enumerate(natural_rows):
        for j, f in enumerate(factors):
            if f.name not in row:
                raise DoeError(f"{row_label} {i}: no value for factor {f.name!r}")
            out[i, j] = f.to_coded(float(row[f.name]))
    return out
