"""demcal's numba DEM engine."""
__version__ = "0.1.0"
