"""Comparing renderers by time and error: Pareto fronts and time ratios at equal error.

Rows are mappings with at least `ms` (time per frame) and `rmse` (error against `reference`), as
the benchmarks produce them. A setting is worth having only if no other is both as fast and as
accurate; and one renderer beats another at equal error when its fastest setting that is at least
as accurate takes less time.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TypeVar

Row = Mapping[str, object]
T = TypeVar("T")


def pareto_front(rows: Iterable[Row]) -> list[Row]:
    """The rows no other row dominates in (ms, rmse), fastest first (so error falls along it)."""
    front: list[Row] = []
    best = float("inf")
    for row in sorted(rows, key=lambda r: (r["ms"], r["rmse"])):
        if row["rmse"] < best:
            front.append(row)
            best = row["rmse"]
    return front


@dataclass(frozen=True)
class Match:
    """A peer's setting and the fastest candidate with equal or lower error (None: no candidate
    reaches the peer's error)."""

    peer: Row
    ours: Row | None

    @property
    def ratio(self) -> float | None:
        """Our time over the peer's: below 1 means ours is faster at equal or lower error."""
        return None if self.ours is None else self.ours["ms"] / self.peer["ms"]


def equal_error(peers: Iterable[Row], candidates: Sequence[Row]) -> list[Match]:
    """For every peer row, the fastest candidate row whose RMSE is at most the peer's."""
    out = []
    for peer in peers:
        better = [r for r in candidates if r["rmse"] <= peer["rmse"]]
        out.append(Match(peer, min(better, key=lambda r: r["ms"]) if better else None))
    return out


def group(items: Iterable[T], key: Callable[[T], object]) -> dict[object, list[T]]:
    """Items by key, keys in order of first appearance."""
    out: dict[object, list[T]] = {}
    for item in items:
        out.setdefault(key(item), []).append(item)
    return out
