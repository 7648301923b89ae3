"""Materials and their laboratory measurements (SI, replicate values kept).

Replicates are stored, not just their mean, because the calibration weights each
target by its standard uncertainty, and that comes from the scatter of replicates.
"""
from __future__ import annotations

import math
from datetime import datetime
from typing import Any

from sqlalchemy import JSON, Boolean, DateTime, Float, ForeignKey, Integer, String, Text
from sqlalchemy.orm import Mapped, mapped_column, relationship

from service.models.base import IDENTITY_LENGTH, Base, utcnow
from service.models.rig import Rig


class Material(Base):
    __tablename__ = "materials"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(200), unique=True, nullable=False)
    description: Mapped[str] = mapped_column(Text, default="", nullable=False)
    source: Mapped[str] = mapped_column(Text, default="", nullable=False)
    bundled: Mapped[bool] = mapped_column(Boolean, default=False, nullable=False)
    # the user (bearer token name) who made it; None without a token (service.ownership)
    owner: Mapped[str | None] = mapped_column(String(IDENTITY_LENGTH), nullable=True)
    # Parameters measured directly (particle density, wall friction ...), usable as priors.
    direct_estimates: Mapped[dict[str, Any]] = mapped_column(JSON, default=dict, nullable=False)
    # The rig its measurements were made in (one laboratory's apparatus, every test kind: engine.lab.rigs);
    # unset for materials stored before rigs existed.
    rig_id: Mapped[int | None] = mapped_column(ForeignKey("rigs.id", ondelete="RESTRICT"), index=True, nullable=True)
    # What it is made of (engine.particles.description.Particles, validated on entry); unset: not given.
    particles: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)
    created_at: Mapped[datetime] = mapped_column(DateTime, default=utcnow, nullable=False)
    updated_at: Mapped[datetime] = mapped_column(DateTime, default=utcnow, onupdate=utcnow, nullable=False)

    rig: Mapped[Rig | None] = relationship(lazy="joined")
    measurements: Mapped[list["Measurement"]] = relationship(
        back_populates="material", cascade="all, delete-orphan", order_by="Measurement.id"
    )


class Measurement(Base):
    """One measured bulk property at one test condition, with its replicates."""

    __tablename__ = "measurements"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    material_id: Mapped[int] = mapped_column(
        ForeignKey("materials.id", ondelete="CASCADE"), index=True, nullable=False
    )
    test: Mapped[str] = mapped_column(String(32), nullable=False)
    quantity: Mapped[str] = mapped_column(String(64), nullable=False)
    condition: Mapped[dict[str, float]] = mapped_column(JSON, default=dict, nullable=False)
    unit: Mapped[str] = mapped_column(String(16), nullable=False)
    values: Mapped[list[float]] = mapped_column(JSON, nullable=False)
    # Set when only a summary was published (e.g. "average of 3"): the replicate
    # count behind a single stored value, and an uncertainty stated by the source.
    reported_replicates: Mapped[int | None] = mapped_column(Integer, nullable=True)
    stated_uncertainty: Mapped[float | None] = mapped_column(Float, nullable=True)
    input_unit: Mapped[str] = mapped_column(String(16), default="", nullable=False)
    source: Mapped[str] = mapped_column(Text, default="", nullable=False)
    created_at: Mapped[datetime] = mapped_column(DateTime, default=utcnow, nullable=False)

    material: Mapped[Material] = relationship(back_populates="measurements")

    @property
    def mean(self) -> float:
        return float(sum(self.values) / len(self.values))

    @property
    def standard_uncertainty(self) -> float | None:
        """Standard uncertainty of the mean: s/sqrt(n) from replicates, else the stated one."""
        if self.stated_uncertainty is not None:
            return float(self.stated_uncertainty)
        n = len(self.values)
        if n < 2:
            return None
        m = self.mean
        s = math.sqrt(sum((v - m) ** 2 for v in self.values) / (n - 1))
        return s / math.sqrt(n)

    def as_dict(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "material_id": self.material_id,
            "test": self.test,
            "quantity": self.quantity,
            "condition": dict(self.condition),
            "unit": self.unit,
            "values": list(self.values),
            "n": len(self.values),
            "reported_replicates": self.reported_replicates,
            "mean": self.mean,
            "standard_uncertainty": self.standard_uncertainty,
            "input_unit": self.input_unit,
            "source": self.source,
            "created_at": self.created_at.isoformat() + "Z" if self.created_at else None,
        }
