"""Test procedures: preparation and simulation; each returns curves and reduced properties."""
