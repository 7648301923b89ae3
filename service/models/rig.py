"""Rigs: the apparatus measurements are made in, stored as validated records (engine.lab.rigs.Rig).

Why the record is one JSON column: its sections (shear box, fill, angle of repose, anchor) are read
whole by the engine and validated whole by ``engine.lab.rigs.Rig``; columns per dimension would repeat
that model in SQL and need a migration for every new apparatus field.
"""
from __future__ import annotations

from datetime import datetime
from typing import Any

from sqlalchemy import JSON, Boolean, DateTime, Integer, String
from sqlalchemy.orm import Mapped, mapped_column

from service.models.base import IDENTITY_LENGTH, Base, utcnow


class Rig(Base):
    __tablename__ = "rigs"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(200), unique=True, nullable=False)
    # bundled records (the thesis's and Appendix A's rigs) are read-only: results name them
    bundled: Mapped[bool] = mapped_column(Boolean, default=False, nullable=False)
    record: Mapped[dict[str, Any]] = mapped_column(JSON, nullable=False)
    # the user (bearer token name) who made it; None without a token (service.ownership)
    owner: Mapped[str | None] = mapped_column(String(IDENTITY_LENGTH), nullable=True)
    created_at: Mapped[datetime] = mapped_column(DateTime, default=utcnow, nullable=False)
    updated_at: Mapped[datetime] = mapped_column(DateTime, default=utcnow, onupdate=utcnow, nullable=False)
