"""The tetrahedral ray caster: `traversal` (the numba kernel walking rays from cell to cell) and
`renderer` (the `tetra` renderer around it)."""
