"""OpenAPI links: from the operation that creates a resource to every operation on that resource.

Why: a client (and schemathesis's stateful phase in CI) learns from the document that the ``id`` a
``POST /jobs`` answers is the ``job_id`` of ``GET /jobs/{job_id}``, ``POST /jobs/{job_id}/cancel`` and the rest,
and likewise for materials, campaigns and schedules. Inferred links missed most of them (a run covered 6 of the
operations on a created campaign, job or schedule), so chains of calls rarely reached a created row.
The rule: a ``POST`` on a top-level collection (``/api/v1/jobs``) whose success response is 201 links to each
operation under ``<collection>/{<param>}``, passing ``$response.body#/id`` as ``<param>``; copies
(``POST /materials/{material_id}/copy``) link the same way. Nested collections (a material's measurements) are
reached through their parent's links.
"""
from __future__ import annotations

import re
from typing import Any

_PARAM = re.compile(r"^\{(\w+)\}$")


def _collection(path: str) -> str | None:
    """The top-level collection a creating POST adds to: ``/api/v1/jobs`` itself, or that of a ``/copy``."""
    if path.endswith("/copy"):
        path = path.rsplit("/", 2)[0]
    return path if "{" not in path else None


def add_links(schema: dict[str, Any]) -> None:
    """Add ``links`` to each creating POST's 201 response in ``schema`` (an OpenAPI document, changed in place)."""
    paths = schema.get("paths", {})
    for path, operations in paths.items():
        created = operations.get("post", {}).get("responses", {}).get("201")
        collection = _collection(path)
        if created is None or collection is None:
            continue
        links: dict[str, Any] = {}
        for target, target_operations in paths.items():
            rest = target[len(collection) + 1:].split("/") if target.startswith(collection + "/") else []
            param = _PARAM.match(rest[0]) if rest else None
            if param is None:
                continue
            for operation in target_operations.values():
                if "operationId" in operation:
                    links[operation["operationId"]] = {
                        "operationId": operation["operationId"],
                        "parameters": {param.group(1): "$response.body#/id"},
                    }
        if links:
            created.setdefault("links", {}).update(links)
