"""The per material-pair property table the kernels read (rows for particle-particle, then particle-wall).

Row of a particle-particle contact between materials a and b: a * n + b; of a particle-wall contact
(particle material a, wall material m): n * n + a * n + m. Combination rules where no override is
given: friction = min (PFC), stiffness ratio and damping ratios = mean (particle-wall: the particle's).
Particle-wall friction is the wall's own value, not this table's.
"""
from __future__ import annotations

import numpy as np

from .config import SimulationConfig
from .effects import get as get_effect
from .kernelgen import Layout


def build_props(config: SimulationConfig, layout: Layout) -> np.ndarray:
    mats = config.materials
    n = len(mats)
    props = np.zeros((2 * n * n, layout.n_props))
    overrides = {}
    for o in config.pair_overrides:
        overrides[(o.material_a, o.material_b)] = o
        overrides[(o.material_b, o.material_a)] = o
    for ctype in ("particle-particle", "particle-wall"):
        for a in range(n):
            for b in range(n):
                ma, mb = mats[a], mats[b]
                if ctype == "particle-particle":
                    row = a * n + b
                    vals = [0.5 * (ma.shear_to_normal_stiffness_ratio + mb.shear_to_normal_stiffness_ratio),
                            0.5 * (ma.damping_ratio_normal + mb.damping_ratio_normal),
                            0.5 * (ma.damping_ratio_shear + mb.damping_ratio_shear),
                            min(ma.friction, mb.friction)]
                else:
                    row = n * n + a * n + b
                    vals = [ma.shear_to_normal_stiffness_ratio, ma.damping_ratio_normal, ma.damping_ratio_shear,
                            ma.friction]
                o = overrides.get((a, b))
                if o is not None:
                    if o.friction is not None:
                        vals[3] = o.friction
                    if o.damping_ratio_normal is not None:
                        vals[1] = o.damping_ratio_normal
                    if o.damping_ratio_shear is not None:
                        vals[2] = o.damping_ratio_shear
                props[row, :4] = vals
                for spec in config.effects:
                    if ctype not in spec.contact_types:
                        continue
                    if spec.materials is not None and (a, b) not in spec.materials and (b, a) not in spec.materials:
                        continue
                    eff = get_effect(spec.name)
                    k = layout.effects.index(eff)
                    off = layout.prop_offsets[k]
                    params = eff.params_model.model_validate(spec.params)
                    vals_e = eff.pair_props(params, ctype, ma, mb)
                    props[row, off] = 1.0
                    props[row, off + 1:off + 1 + eff.n_props] = vals_e
    return props
