"""Alembic schema history for demcal (configured in code by ``service.migrate``)."""
