"""Polynomial model terms in coded units and their conversion to natural units.

A term is a tuple of exponents, one per factor: (1, 1, 0, 0) is AB, (2, 0, 0, 0)
is A^2. Coefficients are fitted in coded units (orthogonal, comparable); the
natural-unit equation, the form the thesis prints (Eq. A.3), is obtained by
expanding x = (z - centre) / half_range, where z is the natural value (or its
log10 for log-scale factors). That expansion is linear in the coefficients, so it
also carries their covariance across.
"""
from __future__ import annotations

import itertools
import re

import numpy as np

from .factors import DoeError

Term = tuple[int, ...]


def term_label(term: Term, letters: str) -> str:
    if not any(term):
        return "Intercept"
    return "".join(letters[i] + ("^2" if p == 2 else f"^{p}" if p > 2 else "") for i, p in enumerate(term) if p)


def term_name(term: Term, factors) -> str:
    """Natural-unit label: 'rho_p*mu_pp', 'k_p^2'."""
    if not any(term):
        return "const"
    return "*".join(f.symbol + (f"^{p}" if p > 1 else "") for f, p in zip(factors, term) if p)


def mask_to_term(mask: int, k: int) -> Term:
    return tuple(1 if mask >> i & 1 else 0 for i in range(k))


def term_to_mask(term: Term) -> int | None:
    """Two-level word of a multilinear term; None for quadratic terms."""
    if any(p > 1 for p in term):
        return None
    return sum(1 << i for i, p in enumerate(term) if p)


def parse_term(text: str, factors) -> Term:
    """'AB', 'A^2', 'rho_p*mu_pp', 'rho_p:mu_pp', 'k_p^2' -> exponent tuple."""
    k = len(factors)
    letters = "".join(f.letter for f in factors)
    names = {f.name: i for i, f in enumerate(factors)}
    s = text.strip()
    exps = [0] * k
    if re.fullmatch(r"([A-Z](\^\d)?)+", s) and all(ch in letters for ch in re.sub(r"\^\d", "", s)) \
            and s not in names:
        for ch, p in re.findall(r"([A-Z])(?:\^(\d))?", s):
            exps[letters.index(ch)] += int(p or 1)
    else:
        for part in re.split(r"[*:]", s):
            part = part.strip()
            m = re.fullmatch(r"(.+?)(?:\^(\d))?", part)
            name, p = m.group(1), int(m.group(2) or 1)
            if name.startswith("log10(") and name.endswith(")"):
                name = name[6:-1]
            if name not in names:
                raise DoeError(f"model term {text!r}: unknown factor {name!r}")
            exps[names[name]] += p
    if not any(exps):
        raise DoeError(f"model term {text!r} is empty")
    if max(exps) > 2:
        raise DoeError(f"model term {text!r}: powers above 2 are not supported")
    return tuple(exps)


def sort_terms(terms) -> list[Term]:
    def key(t):
        quad = any(p > 1 for p in t)
        return (sum(t), quad, [-p for p in t])
    return sorted(set(terms), key=key)


def model_matrix(coded: np.ndarray, terms) -> np.ndarray:
    """Columns: intercept, then one per term."""
    coded = np.atleast_2d(np.asarray(coded, dtype=float))
    cols = [np.ones(coded.shape[0])]
    for t in terms:
        c = np.ones(coded.shape[0])
        for i, p in enumerate(t):
            if p:
                c = c * coded[:, i] ** p
        cols.append(c)
    return np.column_stack(cols)


def parents(term: Term) -> list[Term]:
    """Lower-order terms that hierarchy requires when `term` is in the model."""
    ranges = [range(p + 1) for p in term]
    return [t for t in itertools.product(*ranges) if any(t) and t != term]


def _poly_mul(a: dict, b: dict) -> dict:
    out: dict = {}
    for ea, ca in a.items():
        for eb, cb in b.items():
            e = tuple(x + y for x, y in zip(ea, eb))
            out[e] = out.get(e, 0.0) + ca * cb
    return out


def natural_transform(terms, factors) -> tuple[list[Term], np.ndarray]:
    """Matrix M with natural_coefficients = M @ coded_coefficients (intercept first)."""
    k = len(factors)
    zero = (0,) * k
    expansions = [{zero: 1.0}]
    for t in terms:
        poly = {zero: 1.0}
        for i, p in enumerate(t):
            e1 = tuple(1 if j == i else 0 for j in range(k))
            lin = {zero: -factors[i].centre_t / factors[i].half_range_t, e1: 1.0 / factors[i].half_range_t}
            for _ in range(p):
                poly = _poly_mul(poly, lin)
        expansions.append(poly)
    monos = [zero] + sort_terms(m for e in expansions for m in e if any(m))
    idx = {m: r for r, m in enumerate(monos)}
    M = np.zeros((len(monos), len(expansions)))
    for c, e in enumerate(expansions):
        for m, v in e.items():
            M[idx[m], c] += v
    return monos, M
