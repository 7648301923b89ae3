"""One way to page a listing: filters, a stable order ending in the id, a limit, an offset and the total.

Why the id last: rows that tie on the order (two jobs of one priority) would otherwise come in whatever
order the database likes, and a client paging through could see a row twice or never.
"""
from __future__ import annotations

from typing import Any

from sqlalchemy import func, select
from sqlalchemy.orm import Session


def paged(session: Session, model: Any, *, where: list | tuple = (), order: list | tuple = (), options: tuple = (),
          limit: int, offset: int) -> tuple[list[Any], int]:
    """``(rows of this page, total rows matching where)``; ``order`` should end in the id (it does if it
    is empty: ascending id)."""
    total = session.scalar(select(func.count(model.id)).where(*where))
    stmt = select(model).where(*where).order_by(*(order or (model.id,))).limit(limit).offset(offset)
    if options:
        stmt = stmt.options(*options)
    return list(session.scalars(stmt).all()), int(total or 0)
