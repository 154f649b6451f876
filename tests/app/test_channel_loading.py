"""The app's loader reads a file of several channels with its channels (no --channels needed), as
napari's and OMERO's channel lists do; a one-field file and a chosen array stay one field."""

from __future__ import annotations

import numpy as np

from volren.app.core.loading import load_input
from volren.app.core.state import ViewState, default_camera
from volren.io import load_volume


def test_an_array_of_several_components_opens_as_channels(shared_data):
    path = shared_data / "multichannel" / "stroke_t1_t2_flair.vti"
    loaded = load_input(path)
    channels = loaded.volume.channels
    assert channels is not None and channels.count == 3
    assert channels.value_ranges == ((0.0, 252.0), (0.0, 251.0), (0.0, 255.0))  # T1, T2, FLAIR (MANIFEST.md)
    np.testing.assert_array_equal(channels.values, load_volume(path, channels=True).channels.values)
    state = ViewState(renderer="raycast")
    state.load(loaded.volume, loaded.transfer_function, default_camera(loaded.volume))
    ctf = state.channel_transfer_function
    assert state.channels_drawn and ctf.count == 3 and ctf.visible == [True, True, True]
    assert state.transfer_function is ctf.tfs[0] and state.drawn_transfer_function is ctf
    # the CLI's default look: a ramp over each channel's range, in the palette's colours
    _, alpha = ctf.tfs[2].sample(np.array([0.0, 255.0]))
    np.testing.assert_allclose(alpha, [0.0, 0.2])
    state.select_channel(2)
    assert state.transfer_function is ctf.tfs[2]


def test_a_chosen_component_and_a_one_field_file_stay_one_field(shared_data):
    path = shared_data / "multichannel" / "stroke_t1_t2_flair.vti"
    assert load_input(path, scalars="T1_T2_FLAIR:x").volume.channels is None
    assert load_input(shared_data / "uniform" / "aneurism.vti").volume.channels is None
