"""Declarative base shared by every ORM module (Alembic compares against its metadata)."""
from __future__ import annotations

from datetime import datetime, timezone

from sqlalchemy import MetaData
from sqlalchemy.orm import DeclarativeBase

# Stable constraint names so Alembic batch migrations on SQLite can find them again.
NAMING_CONVENTION = {
    "ix": "ix_%(column_0_label)s",
    "uq": "uq_%(table_name)s_%(column_0_name)s",
    "ck": "ck_%(table_name)s_%(constraint_name)s",
    "fk": "fk_%(table_name)s_%(column_0_name)s_%(referred_table_name)s",
    "pk": "pk_%(table_name)s",
}
# Who made a row or whose limits it counts against (``owner``, ``client_id``): a token's user name, an
# address, ``token:<name>`` or ``schedule:<id>``. One width, so the security module can bound user names by it.
IDENTITY_LENGTH = 100


class Base(DeclarativeBase):
    metadata = MetaData(naming_convention=NAMING_CONVENTION)


def utcnow() -> datetime:
    """Naive UTC everywhere: SQLite drops tz info, so all tables store naive UTC."""
    return datetime.now(timezone.utc).replace(tzinfo=None)
