"""Who may change a stored object: the user who made it, or an administrator (issue 32, item 2).

Every job, material, campaign and schedule records its ``owner``: the name of the bearer token that made it
(``service.security``). With tokens configured, a write to another user's object is a 403 naming the owner;
an administrator (``name:token:admin``, or the single ``DEMCAL_TOKEN``) may change anything. Objects with no
owner (made before ownership existed, made on a server without tokens, or the bundled material) can be
changed only by an administrator once tokens are configured. Without any token (one user on loopback)
nothing is checked: there is only one user.

Reads are not restricted per user: a team shares its materials, campaigns and results; the token guard
decides whether reads need a token at all.
"""
from __future__ import annotations

from dataclasses import dataclass

from fastapi import Request

from service.errors import Forbidden


@dataclass(frozen=True)
class Caller:
    """The user behind a request: ``user`` is None without a token; ``enforced`` when tokens are configured."""

    user: str | None
    admin: bool
    enforced: bool

    def may_change(self, owner: str | None) -> bool:
        return not self.enforced or self.admin or (owner is not None and owner == self.user)

    def require(self, owner: str | None, what: str, field: str | list) -> None:
        """403 unless this caller may change an object of ``owner``; ``what`` is e.g. ``"job 7"``."""
        if self.may_change(owner):
            return
        whose = (f"belongs to {owner!r}" if owner is not None
                 else "has no owner (made before ownership or without a token)")
        raise Forbidden(f"{what} {whose}; only its owner or an administrator may change it (you are "
                        f"{self.user!r})", field)


def caller(request: Request) -> Caller:
    """FastAPI dependency: the request's user, as the token guard (``install_token_guard``) found it."""
    enforced = bool(getattr(request.app.state, "tokens_configured", False))
    return Caller(user=getattr(request.state, "client_name", None),
                  admin=bool(getattr(request.state, "is_admin", False)), enforced=enforced)


def owner_of(request: Request) -> str | None:
    """FastAPI dependency: the owner a new object records (the token's user name, None without one)."""
    return getattr(request.state, "client_name", None)
