"""Bind address policy, bearer token for writes, and per-job resource limits.

Off loopback, anyone on the network could queue hour-long DEM runs, so every
write (POST/PUT/PATCH/DELETE) then needs ``Authorization: Bearer <token>``. The
limits stop runaway jobs before they are queued: particle count and simulated
time are *estimated* from the spec with the lab's fidelity presets (container,
particle sizes, lab speeds), before anything is queued.
"""
from __future__ import annotations

import hmac
import ipaddress
import math
import re

from fastapi import FastAPI, Request
from fastapi.responses import JSONResponse

from engine.lab.context import RunContext
from engine.lab.presets import fidelity
from engine.lab.spec import JobSpec
from service.config import Settings
from service.errors import Invalid, Unauthorized

WRITE_METHODS = frozenset({"POST", "PUT", "PATCH", "DELETE"})

# The thesis's DST holds each normal stress ~20 s to stabilise before shearing (Sec. 4.4).
_DST_STABILISATION_S = 20.0


def is_loopback(host: str) -> bool:
    if host in ("localhost", ""):
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def check_bind(settings: Settings) -> None:
    """Refuse to serve off loopback without a token (raised before the socket opens)."""
    if not is_loopback(settings.host) and not settings.token:
        raise SystemExit(
            f"refusing to bind {settings.host}: set DEMCAL_TOKEN (write endpoints need a bearer token off loopback)"
        )


def install_token_guard(app: FastAPI, settings: Settings) -> None:
    """Writes need the token whenever one is configured (always, off loopback)."""
    if not settings.token:
        return
    expected = settings.token.encode()

    @app.middleware("http")
    async def _require_token(request: Request, call_next):
        if request.method in WRITE_METHODS:
            header = request.headers.get("authorization", "")
            scheme, _, supplied = header.partition(" ")
            if scheme.lower() != "bearer" or not hmac.compare_digest(supplied.strip().encode(), expected):
                err = Unauthorized("missing or wrong bearer token", ["header", "Authorization"])
                return JSONResponse({"detail": err.detail()}, status_code=401,
                                    headers={"WWW-Authenticate": "Bearer"})
        return await call_next(request)


def _preset(spec: JobSpec):
    try:
        return fidelity(spec.fidelity, spec.parameters.particle_radius_m)
    except ValueError as exc:
        raise Invalid(str(exc), "parameters.particle_radius_m") from None


def estimated_particles(spec: JobSpec) -> int:
    """Particles filling the fidelity's container: solids volume / mean particle volume."""
    preset = _preset(spec)
    mean_volume_m3 = sum(
        shape.volume_fraction * 4.0 / 3.0 * math.pi * (0.5 * (shape.radius_min_m + shape.radius_max_m)) ** 3
        for shape in preset.shapes
    )
    solids_m3 = preset.container_area_m2 * preset.packing_height_m * preset.expected_solid_fraction
    return int(math.ceil(solids_m3 * preset.fill_margin / mean_volume_m3))


def estimated_simulated_time_s(spec: JobSpec) -> float:
    """The DST's slow shearing dominates: per normal stress, stabilise then shear at lab speed x factor."""
    preset = _preset(spec)
    speed_factor = spec.options.speed_factor or preset.default_speed_factor
    distance_m = spec.options.shear_distance_m or preset.shear_distance_m
    per_stress_s = _DST_STABILISATION_S + distance_m / (preset.lab_shear_speed_m_s * speed_factor)
    if spec.test not in ("dst", "battery"):
        return per_stress_s
    stresses = len(spec.options.dst_normal_stresses_pa or preset.dst_normal_stresses_pa)
    return stresses * per_stress_s


def validate_spec(spec: JobSpec) -> None:
    """The lab's own pre-run checks (e.g. DST stresses above the CCT maximum), as a 422 at submission
    rather than a failed job later; the lab's messages start with the field path."""
    _preset(spec)  # an unknown fidelity / misplaced particle radius, with its own field
    try:
        RunContext.from_spec(spec).validate()
    except ValueError as exc:
        message = str(exc)
        match = re.match(r"((?:options|parameters)\.[a-z_0-9]+)(:?)\s*", message)
        if match is None:
            raise Invalid(message, "options") from None
        raise Invalid(message[match.end():] if match.group(2) else message, match.group(1)) from None


def check_limits(spec: JobSpec, settings: Settings, field_prefix: str = "") -> None:
    validate_spec(spec)
    particles = estimated_particles(spec)
    if particles > settings.max_particles:
        raise Invalid(
            f"about {particles} particles exceeds the limit of {settings.max_particles}"
            " (raise particle_radius_m or DEMCAL_MAX_PARTICLES)",
            f"{field_prefix}parameters.particle_radius_m" if spec.fidelity == "screening" else f"{field_prefix}fidelity",
        )
    sim_s = estimated_simulated_time_s(spec)
    if sim_s > settings.max_simulated_time_s:
        raise Invalid(
            f"about {sim_s:.0f} s of simulated time exceeds the limit of {settings.max_simulated_time_s:.0f} s"
            " (raise options.speed_factor or DEMCAL_MAX_SIMULATED_TIME_S)",
            f"{field_prefix}options.speed_factor",
        )
