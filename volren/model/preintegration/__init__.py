"""Pre-integrated transfer functions: exact 2D and 3D tables in O(n^2) per segment length,
lighting tables, Engel's approximation and a brute-force twin, and a cache.

Modules: `tf_bins` (exact per-bin means of the TF), `subrange` (Lum et al.'s incremental
subrange integration), `brute_force`, `approximate` (integral functions), `segment_math`
(one homogeneous bin), `lengths` (the length axis of 3D tables and opacity/colour correction),
`cache` and `tables` (the public functions; conventions in its docstring).

numba's on-disk cache does not notice edits to the modules a kernel calls into, so stale cache
files are dropped on import (`volren.numba_cache`).
"""

from pathlib import Path

from volren.numba_cache import drop_stale_cache

drop_stale_cache(Path(__file__).parent)

from volren.model.preintegration.cache import TableCache  # noqa: E402
from volren.model.preintegration.lengths import (  # noqa: E402
    LengthAxis,
    correct_for_length,
    interpolate_in_length,
)
from volren.model.preintegration.tables import (  # noqa: E402
    TABLE_CACHE,
    LightingTables,
    lighting_tables,
    preintegrate,
    preintegrate_approximate,
    preintegrate_brute_force,
)

__all__ = [
    "TABLE_CACHE",
    "LengthAxis",
    "LightingTables",
    "TableCache",
    "correct_for_length",
    "interpolate_in_length",
    "lighting_tables",
    "preintegrate",
    "preintegrate_approximate",
    "preintegrate_brute_force",
]
