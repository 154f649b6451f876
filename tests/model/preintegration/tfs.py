"""Transfer functions shared by the pre-integration tests."""

from __future__ import annotations

from volren.model.transfer_function import TransferFunction1D


def spiky() -> TransferFunction1D:
    """An opaque spike narrower than most table bins, a step-free ramp and varying colour on [0, 1]."""
    return TransferFunction1D(
        [[0, 1, 0, 0], [0.37, 0, 1, 0], [1, 0, 0, 1]],
        [[0, 0], [0.3, 0], [0.31, 1], [0.322, 0], [0.6, 0.2], [1, 0.5]],
    )


def smooth() -> TransferFunction1D:
    return TransferFunction1D([[0, 1, 0.2, 0], [0.5, 0.1, 1, 0.3], [1, 0, 0.4, 1]], [[0, 0], [1, 0.6]])


def on_nodes(n: int) -> TransferFunction1D:
    """Control points only on the nodes of an n-entry table over [0, 1] (linear between them)."""
    k = n - 1
    return TransferFunction1D(
        [[0, 0.9, 0.1, 0.2], [3 / k, 0.2, 0.8, 0.1], [7 / k, 0.1, 0.3, 0.9], [1, 1, 1, 1]],
        [[0, 0.05], [2 / k, 0.9], [5 / k, 0.1], [9 / k, 1.0], [11 / k, 0.0], [1, 0.3]],
    )
