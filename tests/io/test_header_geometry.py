"""One rule for the spacing and origin a header declares, in every text-header format: non-finite
or zero spacing and a non-finite origin are refused naming the field; a negative spacing mirrors
its axis (the samples keep the positions the header gives them)."""

from __future__ import annotations

import numpy as np
import pytest

from volren.errors import VolrenError
from volren.io import load_volume

DATA = (np.arange(64) % 251).astype(np.uint8)  # x fastest: values[0, 0, :] == 0, 1, 2, 3


def write(folder, fmt: str, spacing: str, origin: str):
    (folder / "d.raw").write_bytes(DATA.tobytes())
    if fmt == "mhd":
        text = (
            f"ObjectType = Image\nNDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\n"
            f"ElementSpacing = {spacing}\nOffset = {origin}\nElementDataFile = d.raw\n"
        )
    elif fmt == "nhdr":
        text = (
            f"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 4\nspacings: {spacing}\nencoding: raw\n"
            f"space origin: ({origin.replace(' ', ',')})\ndata file: d.raw\n"
        )
    elif fmt == "vtk":
        text = (
            f"# vtk DataFile Version 3.0\nx\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 4 4 4\n"
            f"SPACING {spacing}\nORIGIN {origin}\nPOINT_DATA 64\nSCALARS s unsigned_char 1\n"
            f"LOOKUP_TABLE default\n{' '.join(map(str, DATA))}\n"
        )
    else:
        text = (
            f'<?xml version="1.0"?>\n<VTKFile type="ImageData" version="0.1" byte_order="LittleEndian">\n'
            f'<ImageData WholeExtent="0 3 0 3 0 3" Origin="{origin}" Spacing="{spacing}">\n'
            f'<Piece Extent="0 3 0 3 0 3"><PointData Scalars="s"><DataArray type="UInt8" Name="s" '
            f'format="ascii">{" ".join(map(str, DATA))}</DataArray></PointData></Piece></ImageData></VTKFile>\n'
        )
    path = folder / f"grid.{fmt}"
    path.write_text(text)
    return path


FORMATS = ["mhd", "nhdr", "vtk", "vti"]


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("spacing, origin, message", [
    ("nan 1 1", "0 0 0", "finite"),
    ("inf 1 1", "0 0 0", "finite"),
    ("0 1 1", "0 0 0", "zero|positive"),
    ("1 1 1", "nan 0 0", "finite"),
])  # fmt: skip
def test_impossible_geometry_is_refused_in_every_format(tmp_path, fmt, spacing, origin, message):
    path = write(tmp_path, fmt, spacing, origin)
    with pytest.raises(VolrenError, match=message) as exc:
        load_volume(path)
    assert str(exc.value).startswith(str(path)) and "\n" not in str(exc.value)


@pytest.mark.parametrize("fmt", FORMATS)
def test_negative_spacing_mirrors_the_axis_in_every_format(tmp_path, fmt):
    volume = load_volume(write(tmp_path, fmt, "-1 2 1", "0 0 5"))
    assert volume.spacing == (1.0, 2.0, 1.0)
    assert volume.origin == (-3.0, 0.0, 5.0)  # the sample at x = 0 is still at x = 0: now the last
    assert volume.values[0, 0, :].tolist() == [3, 2, 1, 0]
    plain = load_volume(write(tmp_path, fmt, "1 2 1", "0 0 5"))
    assert plain.origin == (0.0, 0.0, 5.0) and plain.values[0, 0, :].tolist() == [0, 1, 2, 3]
