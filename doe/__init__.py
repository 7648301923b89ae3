"""Design of experiments and statistics for calibration; knows nothing of DEM."""
