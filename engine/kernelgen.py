"""Write and import the contact kernel specialised for a set of effects.

The generated module's file name carries a hash of the template, the effect layout and the source
of every kernel module it calls, so numba's on-disk cache (keyed on the file) never serves a kernel
compiled against stale code, and the baseline law pays nothing for effects that are not in use.
"""
from __future__ import annotations

import hashlib
import importlib.util
import inspect
import os
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

from . import blocks, integrate, neighbors, springs, stepping, wallgeom
from . import effects as effects_package
from .effects import get as get_effect
from .effects.base import Effect
from .kernel_template import TEMPLATE

BASE_PROPS = 4  # ks_ratio, damping_ratio_normal, damping_ratio_shear, friction
BASE_HIST = 3  # tangential spring displacement


@dataclass(frozen=True)
class Layout:
    """Where each active effect's columns sit in the property row and history row."""

    effects: tuple[Effect, ...]
    prop_offsets: tuple[int, ...]
    hist_offsets: tuple[int, ...]
    n_props: int
    n_hist: int


def layout_for(names: list[str]) -> Layout:
    effects = []
    for name in names:
        eff = get_effect(name)
        if eff not in effects:
            effects.append(eff)
    effects.sort(key=lambda e: e.name)
    p_off, h_off = [], []
    np_, nh = BASE_PROPS, BASE_HIST
    for eff in effects:
        p_off.append(np_)
        h_off.append(nh)
        np_ += 1 + eff.n_props
        nh += eff.n_hist
    return Layout(tuple(effects), tuple(p_off), tuple(h_off), np_, nh)


def _hooks(layout: Layout) -> dict[str, str]:
    ind = " " * 4
    hooks = {"stiffness": [], "normal_extra": [], "rolling": []}
    imports = []
    for eff, po, ho in zip(layout.effects, layout.prop_offsets, layout.hist_offsets):
        fn = f"_fx_{eff.name}"
        imports.append(f"from {eff.module} import {eff.function} as {fn}")
        sl = f"pe = props[row, {po}:{po + 1 + eff.n_props}]"
        if eff.stage == "stiffness":
            body = f"fn_el, knt, ks = {fn}(pe, delta, r_eff, kn, ks)"
        elif eff.stage == "normal_extra":
            body = f"fn += {fn}(pe, delta, r_i, r_j, dist, fn_el)"
        else:
            body = (f"a0, a1, a2 = {fn}(pe, hist[hp], {ho}, n0, n1, n2, w0, w1, w2, fn_el, r_eff, knt, ks, i_roll, dt)\n"
                    f"{ind * 2}tr0 += a0\n{ind * 2}tr1 += a1\n{ind * 2}tr2 += a2")
        hooks[eff.stage].append(f"{ind}{sl}\n{ind}if pe[0] != 0.0:\n{ind * 2}{body}")
    return {
        "N_HIST": str(layout.n_hist),
        "EFFECT_NAMES": ", ".join(e.name for e in layout.effects) or "none",
        "EFFECT_IMPORTS": "\n".join(imports),
        "STIFFNESS_HOOKS": "\n".join(hooks["stiffness"]),
        "NORMAL_EXTRA_HOOKS": "\n".join(hooks["normal_extra"]),
        "ROLLING_HOOKS": "\n".join(hooks["rolling"]),
        "ROOT_KNT": "math.sqrt(knt * m_eff)" if hooks["stiffness"] else "root_km",
        "ROLL_INERTIA": "pair_rolling_inertia(b_mass[bi], b_mass[bj], r_i, r_j)" if hooks["rolling"] else "0.0",
    }


def kernel_source(layout: Layout) -> str:
    src = TEMPLATE
    for key, value in _hooks(layout).items():
        src = src.replace("{" + key + "}", value)
    return src


def cache_dir(configured: str | None = None) -> Path:
    path = configured or os.environ.get("DEMCAL_KERNEL_DIR") or os.path.join(
        os.path.expanduser("~"), ".cache", "demcal", "kernels")
    return Path(path)


_LOADED: dict[str, ModuleType] = {}


def load_kernel(layout: Layout, configured_dir: str | None = None) -> ModuleType:
    src = kernel_source(layout)
    digest = hashlib.sha256(src.encode())
    for mod in (blocks, integrate, neighbors, springs, stepping, wallgeom):
        digest.update(inspect.getsource(mod).encode())
    # every module of the effects package, helpers shared by several effects included: numba's cache
    # of this kernel does not notice when a function it inlined from another module changes
    for path in sorted(Path(effects_package.__file__).parent.glob("*.py")):
        digest.update(path.read_bytes())
    name = "demcal_kernel_" + digest.hexdigest()[:16]
    if name in _LOADED:
        return _LOADED[name]
    folder = cache_dir(configured_dir)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.py"
    if not path.exists() or path.read_text() != src:
        # write atomically so concurrent workers never import a half-written file
        fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
        with os.fdopen(fd, "w") as fh:
            fh.write(src)
        os.replace(tmp, path)
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    _LOADED[name] = module
    return module
