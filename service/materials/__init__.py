"""Materials and measurements: SI storage, unit conversion at the edge, bundled thesis material."""
from service.materials.store import seed_bundled_materials

__all__ = ["seed_bundled_materials"]
