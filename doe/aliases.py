"""Alias structure of a two-level design, computed from its runs.

Working from the sign columns rather than from the generators means the same
code checks what pydoe3 returned, handles fold-overs (whose generators change)
and any design a user uploads. A word is a bitmask over factor indices.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .factors import LETTERS, DoeError

ROMAN = {1: "I", 2: "II", 3: "III", 4: "IV", 5: "V", 6: "VI", 7: "VII", 8: "VIII"}
_MAX_FULL_K = 12  # beyond this only words up to order 4 are enumerated


def word_label(mask: int, letters: str = LETTERS) -> str:
    return "".join(letters[i] for i in range(mask.bit_length()) if mask >> i & 1) or "I"


def word_order(mask: int) -> int:
    return bin(mask).count("1")


def parse_word(text: str, letters: str) -> tuple[int, int]:
    """'ABC' or '-ABC' -> (mask, sign)."""
    text = text.strip().upper()
    sign = 1
    if text.startswith(("-", "+")):
        sign = -1 if text[0] == "-" else 1
        text = text[1:]
    mask = 0
    for ch in text:
        if ch not in letters:
            raise DoeError(f"unknown factor letter {ch!r} in {text!r} (factors are {letters})")
        bit = 1 << letters.index(ch)
        if mask & bit:
            raise DoeError(f"letter {ch!r} repeated in word {text!r}")
        mask |= bit
    if not mask:
        raise DoeError("empty word in generator")
    return mask, sign


def word_column(coded: np.ndarray, mask: int) -> np.ndarray:
    col = np.ones(coded.shape[0])
    for i in range(coded.shape[1]):
        if mask >> i & 1:
            col = col * coded[:, i]
    return col


@dataclass
class AliasChain:
    term: str                 # representative, the label used for the effect
    mask: int
    aliases: list[tuple[str, int]] = field(default_factory=list)  # (word, sign relative to term)
    members: frozenset = frozenset()  # every mask in the chain, shown or not

    @property
    def label(self) -> str:
        """'AB = CD' style, as in the thesis's Table A.4."""
        rest = [("-" if s < 0 else "") + w for w, s in self.aliases]
        return " = ".join([self.term] + rest)

    def to_dict(self) -> dict:
        return {"term": self.term, "aliases": [("-" if s < 0 else "") + w for w, s in self.aliases],
                "label": self.label}


@dataclass
class AliasStructure:
    k: int
    letters: str
    defining_relation: list[tuple[str, int]]  # words aliased with the intercept, with sign
    chains: list[AliasChain]
    resolution: int | None                    # None: no aliasing (full factorial)

    @property
    def resolution_label(self) -> str:
        if self.resolution is None:
            return "full factorial (no aliasing)"
        return f"Resolution {ROMAN.get(self.resolution, str(self.resolution))}"

    def chain_of(self, mask: int) -> AliasChain | None:
        for c in self.chains:
            if c.mask == mask or mask in c.members:
                return c
        return None

    def representative(self, mask: int) -> int | None:
        """The estimable word standing for `mask`; None if aliased with the intercept."""
        c = self.chain_of(mask)
        return None if c is None else c.mask

    def to_dict(self) -> dict:
        return {"defining_relation": ["I = " + " = ".join(("-" if s < 0 else "") + w
                                                          for w, s in self.defining_relation)]
                if self.defining_relation else [],
                "resolution": self.resolution, "resolution_label": self.resolution_label,
                "chains": [c.to_dict() for c in self.chains]}

    def summary_lines(self) -> list[str]:
        lines = [self.resolution_label]
        if self.defining_relation:
            lines.append("I = " + " = ".join(("-" if s < 0 else "") + w for w, s in self.defining_relation))
        lines += [c.label for c in self.chains if c.aliases]
        return lines


def _sort_key(mask: int, generated: int):
    # Prefer low order, then words of the base (non-generated) factors, as the thesis
    # labels BC rather than AD in a 2^(4-1) with D = ABC; then alphabetical.
    return (word_order(mask), word_order(mask & generated), word_label(mask))


def alias_structure(coded_factorial: np.ndarray, generated: int | None = None, letters: str = LETTERS,
                    max_display_order: int | None = None) -> AliasStructure:
    """Alias chains of the +-1 runs in `coded_factorial` (rows may repeat).

    `generated` is the bitmask of factors set by generators; None infers it as the
    last letter of each defining word, which is how standard fractions are built.
    """
    pts = np.asarray(coded_factorial, dtype=float)
    if pts.ndim != 2 or pts.shape[0] == 0:
        raise DoeError("alias structure needs at least one factorial run")
    if not np.all(np.isin(pts, (-1.0, 1.0))):
        raise DoeError("alias structure is defined for two-level (+-1) runs only")
    pts = np.unique(pts, axis=0)
    k = pts.shape[1]
    max_order = k if k <= _MAX_FULL_K else 4
    masks = [m for m in range(1, 1 << k) if word_order(m) <= max_order]
    groups: dict[bytes, list[tuple[int, int]]] = {}
    identity: list[tuple[int, int]] = []
    for m in masks:
        col = word_column(pts, m)
        if np.all(col == col[0]):
            identity.append((m, int(col[0])))
            continue
        sign = int(col[np.argmax(col != 0)])  # normalise so the first entry is +1
        key = (col * sign).astype(np.int8).tobytes()
        groups.setdefault(key, []).append((m, sign))
    if generated is None:
        generated = 0
        for m, _ in identity:
            generated |= 1 << (m.bit_length() - 1)
    chains = []
    for members in groups.values():
        members.sort(key=lambda ms: _sort_key(ms[0], generated))
        rep, rep_sign = members[0]
        shown = [(word_label(m, letters), s * rep_sign) for m, s in members[1:]
                 if max_display_order is None or word_order(m) <= max_display_order]
        chains.append(AliasChain(word_label(rep, letters), rep, shown, frozenset(m for m, _ in members)))
    chains.sort(key=lambda c: _sort_key(c.mask, generated))
    identity.sort(key=lambda ms: _sort_key(ms[0], 0))
    resolution = min((word_order(m) for m, _ in identity), default=None)
    return AliasStructure(k, letters[:k],
                          [(word_label(m, letters), s) for m, s in identity], chains, resolution)
