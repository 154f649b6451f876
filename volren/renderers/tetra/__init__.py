"""The tetrahedral ray caster: `traversal` (the numba kernel walking rays from cell to cell) and
`renderer` (the `tetra` renderer around it)."""

from pathlib import Path

from volren.kernels import drop_stale_cache_of

drop_stale_cache_of(Path(__file__).parent)
