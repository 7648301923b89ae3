"""Least squares shared by the fit, the model selection for missing runs and the Box-Cox choice: the residual
sum of squares of y on a model matrix, and that matrix's rank (how many coefficients the runs can tell apart)."""
from __future__ import annotations

import numpy as np


def residual_ss(X: np.ndarray, y: np.ndarray) -> float:
    beta, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ beta
    return float(r @ r)


def rank(X: np.ndarray) -> int:
    return int(np.linalg.matrix_rank(X))
