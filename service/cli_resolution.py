"""The CLI's resolution flags and the cost line shown when a job or campaign is created (issue 29: rig, particles
and resolution; ``engine.lab.resolution``), shared by ``demcal job submit`` and ``demcal campaign create``."""
from __future__ import annotations

from service.cli_http import CliError


def resolution_body(args):
    """--resolution, with --scale-factor or --target-particles making it a coarse resolution's object."""
    if args.scale_factor is None and args.target_particles is None:
        return args.resolution
    if args.resolution not in (None, "coarse"):
        raise CliError("--scale-factor and --target-particles apply to --resolution coarse")
    if args.scale_factor is not None and args.target_particles is not None:
        raise CliError("give --scale-factor or --target-particles, not both")
    key, value = (("scale_factor", args.scale_factor) if args.scale_factor is not None
                  else ("target_particles", args.target_particles))
    return {"mode": "coarse", key: value}


def estimate_line(estimate: dict | None) -> str:
    """The cost shown at creation: where the batteries run and what each costs."""
    if not estimate:
        return ""
    batteries = f", {estimate['batteries']} batteries in the first design" if estimate.get("batteries") else ""
    return (f"each battery: about {estimate['particles']:,} particles, up to {estimate['simulated_time_s']:.0f} s "
            f"simulated, in rig {estimate['rig']} at resolution {estimate['resolution']} "
            f"(sizes x {estimate['scale_factor']:.3g}){batteries}{wall_time_text(estimate)}")


def wall_time_text(estimate: dict) -> str:
    """'; about 4.2 min each here (3.1 min-5.0 min; 12 finished dem jobs of ...)', or '' without a record."""
    if estimate.get("wall_time_s") is None:
        return ""
    low, high = estimate.get("wall_time_range_s") or (None, None)
    spread = f"{_duration(low)}-{_duration(high)}; " if low is not None else ""
    return f"; about {_duration(estimate['wall_time_s'])} each here ({spread}{estimate['wall_time_basis']})"


def _duration(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.1f} min" if seconds < 7200 else f"{seconds / 3600:.1f} h"


def resolution_options(parser) -> None:
    parser.add_argument("--resolution", choices=["as_measured", "coarse", "thesis", "screening"],
                        help="as_measured / coarse: the material's particles in the rig its measurements were made "
                             "in; thesis / screening: the old fidelity presets")
    parser.add_argument("--scale-factor", type=float, help="coarse: particle sizes over the material's")
    parser.add_argument("--target-particles", type=int, help="coarse: demcal proposes the factor for about this many")
