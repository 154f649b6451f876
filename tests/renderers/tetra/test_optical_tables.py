"""The table split that the tetra walk reads equals its closed form, entry by entry."""

import numpy as np

from volren.model.preintegration import LengthAxis, preintegrate
from volren.model.transfer_function import TransferFunction1D
from volren.renderers.tetra.optical_tables import MAX_ALPHA, optical_tables


def test_split_matches_the_closed_form_on_a_table_with_clear_and_opaque_entries() -> None:
    tf = TransferFunction1D([[0.0, 1.0, 0.2, 0.0], [1.0, 0.0, 0.4, 1.0]],
                            [[0.0, 0.0], [0.3, 0.0], [0.6, 0.8], [1.0, 0.0]])  # fmt: skip
    axis = LengthAxis(3.0, 5)
    table = preintegrate(tf, 32, lengths=axis.lengths, value_range=(0.0, 1.0), cache=None)
    depth, ratio = optical_tables(table, axis.lengths[0])

    alpha = np.minimum(table[..., 3].astype(np.float64), MAX_ALPHA)
    assert (alpha == 0).any() and (alpha > 0.5).any()  # both branches are exercised
    np.testing.assert_allclose(depth[..., 0], -np.log1p(-alpha[0]) / axis.lengths[0], rtol=1e-15, atol=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        expected = np.where(alpha[..., None] > 0, table[..., :3] / alpha[..., None], 0.0)
    np.testing.assert_allclose(ratio, expected, rtol=1e-15, atol=0)
