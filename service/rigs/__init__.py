"""Rigs: stored apparatus records (engine.lab.rigs), the bundled ones seeded at start."""
from service.rigs.store import seed_bundled_rigs

__all__ = ["seed_bundled_rigs"]
