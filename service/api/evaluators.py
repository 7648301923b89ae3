"""The evaluator catalogue: every backend a job or campaign can name, served from the registry.

Why an endpoint: the page's evaluator selects, and any client, learn the names, what each one is
and which lab tests it runs from the one declaration (``calibration.evaluator_registry``) instead
of a list written again beside each form.
"""
from __future__ import annotations

from fastapi import APIRouter
from pydantic import BaseModel, Field

from calibration.evaluator_registry import REGISTRY

router = APIRouter(tags=["evaluators"])


class EvaluatorOut(BaseModel):
    name: str = Field(description="what a job's or campaign's `evaluator` field takes")
    title: str = Field(description="a few words for a select's label")
    description: str
    tests: list[str] = Field(description="the lab tests it runs (a job's `test`)")


class EvaluatorCatalogue(BaseModel):
    evaluators: list[EvaluatorOut]


@router.get("/evaluators", response_model=EvaluatorCatalogue,
            summary="Every evaluator a job or campaign can name: title, description, the tests it runs")
def list_evaluators() -> EvaluatorCatalogue:
    return EvaluatorCatalogue(evaluators=[
        EvaluatorOut(name=b.name, title=b.title, description=b.description, tests=list(b.tests))
        for b in REGISTRY.values()])
