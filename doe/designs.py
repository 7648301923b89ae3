"""Two-level factorial designs with centre runs, replicates and seeded run order.

A `Design` keeps its runs in standard (Yates) order, first factor changing
fastest, as Table A.8 of the thesis and Design-Expert list them; `run_order` is
the randomised order in which they should be executed. Every run carries its
own simulator seed so that replicated points (centre runs especially) measure
the seed-to-seed scatter, which is the simulator's noise floor.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import pyDOE3

from .aliases import AliasStructure, alias_structure, parse_word, word_column
from .factors import LETTERS, DoeError, Factor, as_factors

# Standard generators (Montgomery, DAE, Table 8.14) for when none are given.
STANDARD_GENERATORS = {
    (3, 1): ["C=AB"], (4, 1): ["D=ABC"], (5, 1): ["E=ABCD"], (5, 2): ["D=AB", "E=AC"],
    (6, 1): ["F=ABCDE"], (6, 2): ["E=ABC", "F=BCD"], (6, 3): ["D=AB", "E=AC", "F=BC"],
    (7, 1): ["G=ABCDEF"], (7, 2): ["F=ABCD", "G=ABDE"], (7, 3): ["E=ABC", "F=BCD", "G=ACD"],
    (7, 4): ["D=AB", "E=AC", "F=BC", "G=ABC"],
}
POINT_TYPES = ("factorial", "center", "axial", "other")
_SEED_MAX = 2**31 - 1


@dataclass
class Design:
    factors: tuple[Factor, ...]
    coded: np.ndarray            # n x k, rows in standard order
    point_type: list[str]
    run_order: np.ndarray        # 1-based execution order
    replicate: np.ndarray        # 1-based count among runs at the same point
    seed: np.ndarray             # simulator seed per run, all distinct
    block: np.ndarray
    generators: list[str] = field(default_factory=list)
    kind: str = ""
    base_seed: int = 0
    notes: list[str] = field(default_factory=list)
    aliases: AliasStructure | None = None

    def __post_init__(self):
        self.coded = np.asarray(self.coded, dtype=float).reshape(-1, len(self.factors))
        for level in (-1.0, 0.0, 1.0):  # snap round-off from natural -> coded conversion
            self.coded[np.abs(self.coded - level) < 1e-9] = level
        n = self.coded.shape[0]
        for name in ("run_order", "replicate", "seed", "block"):
            setattr(self, name, np.asarray(getattr(self, name), dtype=np.int64).reshape(n))
        if len(self.point_type) != n:
            raise DoeError("point_type length does not match the number of runs")
        if self.aliases is None:
            fac = self.factorial_mask
            if fac.any():
                generated = 0 if self.generators else None
                for g in self.generators:
                    generated |= 1 << self.letters.index(g.split("=")[0].strip().upper())
                self.aliases = alias_structure(self.coded[fac], generated, self.letters)

    # --- views -----------------------------------------------------------------
    @property
    def k(self) -> int:
        return len(self.factors)

    @property
    def n_runs(self) -> int:
        return self.coded.shape[0]

    @property
    def letters(self) -> str:
        return LETTERS[: self.k]

    @property
    def names(self) -> list[str]:
        return [f.name for f in self.factors]

    @property
    def std_order(self) -> np.ndarray:
        return np.arange(1, self.n_runs + 1)

    @property
    def factorial_mask(self) -> np.ndarray:
        return np.array([t == "factorial" for t in self.point_type])

    @property
    def center_mask(self) -> np.ndarray:
        return np.array([t == "center" for t in self.point_type])

    @property
    def natural(self) -> np.ndarray:
        return np.column_stack([f.to_natural(self.coded[:, j]) for j, f in enumerate(self.factors)])

    def factor(self, name: str) -> Factor:
        for f in self.factors:
            if f.name == name or f.letter == name:
                return f
        raise DoeError(f"no factor named {name!r} (factors: {', '.join(self.names)})")

    def records(self, order: str = "std") -> list[dict]:
        """One dict per run: orders, block, type, replicate, seed, natural and coded levels."""
        nat = self.natural
        rows = []
        for i in range(self.n_runs):
            r = {"std_order": i + 1, "run_order": int(self.run_order[i]), "block": int(self.block[i]),
                 "point_type": self.point_type[i], "replicate": int(self.replicate[i]),
                 "seed": int(self.seed[i])}
            r.update({f.name: float(nat[i, j]) for j, f in enumerate(self.factors)})
            r.update({f"{f.letter}_coded": float(self.coded[i, j]) for j, f in enumerate(self.factors)})
            rows.append(r)
        if order == "run":
            rows.sort(key=lambda r: r["run_order"])
        elif order != "std":
            raise DoeError("order must be 'std' or 'run'")
        return rows

    def parameter_sets(self, order: str = "run") -> list[dict[str, float]]:
        """Natural factor values per run, what a batch evaluator receives."""
        return [{f.name: r[f.name] for f in self.factors} for r in self.records(order)]

    def run_to_std(self) -> np.ndarray:
        """Index array: position p in run order -> row in standard order."""
        return np.argsort(self.run_order, kind="stable")

    def to_dict(self) -> dict:
        return {"kind": self.kind, "factors": [f.to_dict() for f in self.factors],
                "generators": list(self.generators), "base_seed": self.base_seed,
                "n_runs": self.n_runs, "runs": self.records("std"),
                "aliases": self.aliases.to_dict() if self.aliases else None, "notes": list(self.notes)}

    @classmethod
    def from_dict(cls, d: dict) -> "Design":
        try:
            factors = as_factors(d["factors"])
            runs = sorted(d["runs"], key=lambda r: r["std_order"])
            coded = np.array([[float(r[f"{f.letter}_coded"]) if f"{f.letter}_coded" in r
                               else float(f.to_coded(r[f.name])) for f in factors] for r in runs])
            return cls(factors, coded, [r.get("point_type", "other") for r in runs],
                       [r["run_order"] for r in runs], [r.get("replicate", 1) for r in runs],
                       [r.get("seed", 0) for r in runs], [r.get("block", 1) for r in runs],
                       list(d.get("generators", [])), d.get("kind", ""), int(d.get("base_seed", 0)),
                       list(d.get("notes", [])))
        except KeyError as exc:
            raise DoeError(f"design definition lacks {exc.args[0]!r}") from None

    @classmethod
    def from_runs(cls, factors, natural_rows, seeds=None) -> "Design":
        """A design from runs already made (e.g. an uploaded CSV), in the order given."""
        factors = as_factors(factors)
        coded = np.array([[float(f.to_coded(float(r[f.name]))) for f in factors] for r in natural_rows])
        for level in (-1.0, 0.0, 1.0):
            coded[np.abs(coded - level) < 1e-9] = level
        types = [classify_point(row) for row in coded]
        n = len(types)
        return cls(factors, coded, types, np.arange(1, n + 1), replicate_index(coded),
                   seeds if seeds is not None else np.zeros(n, dtype=int), np.ones(n, dtype=int),
                   kind="runs as given")

    def summary(self) -> str:
        from .report import design_text
        return design_text(self)


def classify_point(coded_row, tol: float = 1e-6) -> str:
    a = np.abs(np.asarray(coded_row))
    if np.all(np.abs(a - 1) < tol):
        return "factorial"
    if np.all(a < tol):
        return "center"
    if np.sum(a > tol) == 1:
        return "axial"
    return "other"


def replicate_index(coded: np.ndarray) -> np.ndarray:
    """1-based count of each row among the rows at the same coded point (the replicate number)."""
    seen: dict[bytes, int] = {}
    out = []
    for row in np.round(coded, 9):
        key = row.tobytes()
        seen[key] = seen.get(key, 0) + 1
        out.append(seen[key])
    return np.array(out)


def draw_seeds(rng: np.random.Generator, n: int, taken=()) -> np.ndarray:
    """``n`` distinct simulator seeds from ``rng``, none in ``taken`` (calibration.reuse keeps reused seeds)."""
    taken = set(int(s) for s in taken)
    out = []
    while len(out) < n:
        s = int(rng.integers(1, _SEED_MAX))
        if s not in taken:
            taken.add(s)
            out.append(s)
    return np.array(out, dtype=np.int64)


def parse_generators(generators, factors) -> list[tuple[int, int, int]]:
    """['D=ABC', 'E=-AC'] -> [(target index, word mask, sign)], checked for consistency."""
    letters = LETTERS[: len(factors)]
    names = {f.name: f.letter for f in factors}
    items = list(generators.items()) if isinstance(generators, dict) else []
    if not isinstance(generators, dict):
        for g in generators:
            if "=" not in g:
                raise DoeError(f"generator {g!r}: expected the form D=ABC")
            lhs, rhs = g.split("=", 1)
            items.append((lhs, rhs))
    out = []
    for lhs, rhs in items:
        lhs = names.get(lhs.strip(), lhs.strip().upper())
        if len(lhs) != 1 or lhs not in letters:
            raise DoeError(f"generator {lhs}={rhs}: {lhs!r} is not one of the factor letters {letters}")
        mask, sign = parse_word(rhs, letters)
        out.append((letters.index(lhs), mask, sign))
    targets = {t for t, _, _ in out}
    if len(targets) != len(out):
        raise DoeError("each factor may be generated only once")
    for t, mask, _ in out:
        if mask >> t & 1 or any(mask >> u & 1 for u in targets):
            raise DoeError(f"generator for {letters[t]} must use base factors only "
                           f"(base: {''.join(letters[i] for i in range(len(factors)) if i not in targets)})")
        if bin(mask).count("1") < 2:
            raise DoeError(f"generator for {letters[t]} must be an interaction of two or more base factors")
    return out


def _yates(k: int) -> np.ndarray:
    i = np.arange(2**k)[:, None]
    return np.where((i >> np.arange(k)) & 1, 1.0, -1.0)


def _factorial_core(factors, gens) -> np.ndarray:
    """2^(k-p) points in Yates order of the base factors; built by pydoe3, then checked."""
    k = len(factors)
    targets = [t for t, _, _ in gens]
    base = [j for j in range(k) if j not in targets]
    if not gens:
        return _yates(k)
    rel = {j: "abcdefghijklmnopqrstuvwxyz"[i] for i, j in enumerate(base)}
    tokens = [rel[j] for j in base]
    for _, mask, sign in gens:
        tokens.append(("-" if sign < 0 else "") + "".join(rel[j] for j in base if mask >> j & 1))
    raw = pyDOE3.fracfact(" ".join(tokens))
    pts = np.empty_like(raw)
    pts[:, base] = raw[:, : len(base)]
    for c, (t, _, _) in enumerate(gens):
        pts[:, t] = raw[:, len(base) + c]
    # check what pydoe3 returned: every generated column is the signed product
    for t, mask, sign in gens:
        if not np.array_equal(pts[:, t], sign * word_column(pts, mask)):
            raise DoeError("pydoe3.fracfact returned columns that break the generators")
    order = np.lexsort(tuple(pts[:, j] for j in base))  # first base factor fastest
    pts = pts[order]
    if not np.array_equal(pts[:, base], _yates(len(base))):
        raise DoeError("pydoe3.fracfact did not return every base-factor combination")
    return pts


def _finish(factors, core, *, center_runs, replicates, seed, randomize, generators, kind) -> Design:
    if replicates < 1:
        raise DoeError("replicates must be at least 1")
    if center_runs < 0:
        raise DoeError("center_runs cannot be negative")
    k = len(factors)
    coded = np.vstack([np.tile(core, (replicates, 1)), np.zeros((center_runs, k))])
    types = ["factorial"] * (core.shape[0] * replicates) + ["center"] * center_runs
    rng = np.random.default_rng(seed)
    n = coded.shape[0]
    run_order = (rng.permutation(n) + 1) if randomize else np.arange(1, n + 1)
    seeds = draw_seeds(np.random.default_rng([seed, 1]), n)
    return Design(factors, coded, types, run_order, replicate_index(coded), seeds,
                  np.ones(n, dtype=int), generators, kind, int(seed))


def fractional_factorial(factors, generators=None, *, center_runs: int = 0, replicates: int = 1,
                         seed: int = 0, randomize: bool = True) -> Design:
    """2^(k-p) design from explicit generators such as ['D=ABC'] (the default for 4 factors)."""
    factors = as_factors(factors)
    k = len(factors)
    if generators is None:
        candidates = [g for (kk, p), g in STANDARD_GENERATORS.items() if kk == k and p == 1]
        if not candidates:
            raise DoeError(f"give explicit generators for {k} factors (e.g. --generators D=ABC)")
        generators = candidates[0]
    gens = parse_generators(generators, factors)
    core = _factorial_core(factors, gens)
    labels = [f"{LETTERS[t]}={'-' if s < 0 else ''}"
              + "".join(LETTERS[j] for j in range(k) if m >> j & 1) for t, m, s in gens]
    kind = f"2^({k}-{len(gens)}) fractional factorial" if gens else f"2^{k} full factorial"
    return _finish(factors, core, center_runs=center_runs, replicates=replicates, seed=seed,
                   randomize=randomize, generators=labels, kind=kind)


def full_factorial(factors, *, center_runs: int = 0, replicates: int = 1, seed: int = 0,
                   randomize: bool = True) -> Design:
    return fractional_factorial(factors, [], center_runs=center_runs, replicates=replicates,
                                seed=seed, randomize=randomize)


def _append(design: Design, coded_new, types_new, kind, notes, salt: int) -> Design:
    """New runs go in a new block, with fresh seeds, executed after the existing ones."""
    coded_new = np.asarray(coded_new, dtype=float).reshape(-1, design.k)
    n_new = coded_new.shape[0]
    rng = np.random.default_rng([design.base_seed, salt, design.n_runs])
    order_new = design.run_order.max(initial=0) + rng.permutation(n_new) + 1
    seeds_new = draw_seeds(rng, n_new, design.seed)
    coded = np.vstack([design.coded, coded_new])
    return replace(design, coded=coded, point_type=design.point_type + list(types_new),
                   run_order=np.concatenate([design.run_order, order_new]),
                   replicate=replicate_index(coded), seed=np.concatenate([design.seed, seeds_new]),
                   block=np.concatenate([design.block, np.full(n_new, design.block.max() + 1)]),
                   kind=kind, notes=design.notes + notes, aliases=None)


def foldover(design: Design, factor: str, center_runs: int = 0) -> Design:
    """Single-factor fold-over: repeat the factorial runs with one factor's sign reversed.

    This frees that factor's main effect and its two-factor interactions from aliasing.
    """
    f = design.factor(factor)
    j = design.names.index(f.name)
    core = np.unique(design.coded[design.factorial_mask], axis=0)
    if core.shape[0] == 2**design.k:
        raise DoeError("the design is already a full factorial; a fold-over adds nothing")
    new = core.copy()
    new[:, j] *= -1
    order = np.lexsort(tuple(new[:, c] for c in range(design.k)))
    new = np.vstack([new[order], np.zeros((center_runs, design.k))])
    types = ["factorial"] * core.shape[0] + ["center"] * center_runs
    return _append(design, new, types, design.kind + f" + fold-over on {f.letter} ({f.name})",
                   [f"fold-over on {f.name} in block {design.block.max() + 1}"], 11)


def rotatable_alpha(design: Design) -> float:
    n_f = np.unique(design.coded[design.factorial_mask], axis=0).shape[0]
    return float(n_f ** 0.25)


def augment_ccd(design: Design, alpha="face", center_runs: int = 2) -> Design:
    """Add axial (star) runs and centre runs in a new block: a central composite design.

    alpha='face' keeps every run inside the factor box; 'rotatable' uses n_F^(1/4),
    which puts axial runs outside the box (natural levels beyond low/high).
    """
    if not design.factorial_mask.any():
        raise DoeError("augmentation to a CCD needs a two-level factorial to start from")
    if any(t == "axial" for t in design.point_type):
        raise DoeError("the design already has axial runs")
    if alpha in ("face", "faced", "face-centred", "face-centered"):
        a, label = 1.0, "face-centred"
    elif alpha == "rotatable":
        a, label = rotatable_alpha(design), "rotatable"
    else:
        try:
            a, label = float(alpha), f"alpha={float(alpha):g}"
        except (TypeError, ValueError):
            raise DoeError("alpha must be 'face', 'rotatable' or a number") from None
        if a <= 0:
            raise DoeError("alpha must be positive")
    star = pyDOE3.doe_star.star(design.k, alpha="faced")[0] * a
    if star.shape != (2 * design.k, design.k) or not np.allclose(np.abs(star).sum(axis=1), a):
        raise DoeError("pydoe3 star points are not one factor at +-alpha")
    new = np.vstack([star, np.zeros((center_runs, design.k))])
    types = ["axial"] * star.shape[0] + ["center"] * center_runs
    notes = [f"CCD {label}: alpha = {a:.4g} in block {design.block.max() + 1}"]
    if a > 1:
        for j, f in enumerate(design.factors):
            lo, hi = f.to_natural(-a), f.to_natural(a)
            if (f.low > 0 and lo <= 0) or (f.high < 0 and hi >= 0):
                notes.append(f"axial level of {f.name} ({lo:g}) changes sign; check it is physical")
    res = design.aliases.resolution if design.aliases else None
    if res is not None and res < 5:
        notes.append(f"factorial core is resolution {res}: some two-factor interactions stay aliased")
    return _append(design, new, types, design.kind + f" + CCD ({label})", notes, 23)


def make_design(factors, generators=None, *, full: bool = False, center_runs: int = 0, replicates: int = 1,
                seed: int = 0, randomize: bool = True) -> Design:
    """One call for campaigns: a full factorial (k <= 3 or full=True) or a half fraction.

    Four factors default to the thesis's 2^(4-1) with D = ABC (Table A.8).
    `factors` may be dicts {name, low, high, unit, log}.
    """
    factors = as_factors(factors)
    if full or (generators is None and len(factors) <= 3) or generators == []:
        return full_factorial(factors, center_runs=center_runs, replicates=replicates, seed=seed,
                              randomize=randomize)
    return fractional_factorial(factors, generators, center_runs=center_runs, replicates=replicates,
                                seed=seed, randomize=randomize)
