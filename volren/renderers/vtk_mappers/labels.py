"""Label volumes on VTK's GPU ray caster through its label-map mask (Real-Time Volume Graphics,
chapter 16: a transfer function per object).

vtkGPUVolumeRayCastMapper with a uint8 mask (SetMaskInput, SetMaskTypeToLabelMap) classifies each
sample with its label's TF (vtkVolumeProperty.SetLabelColor / SetLabelScalarOpacity), label 0 with
the property's own TF. Two differences from volren's model (`volren.model.labels`), measured on the
kit's label scenes (VTK 9.7.2, llvmpipe, step 0.5):
- VTK takes one label per sample where the model blends the labels' classified samples by their
  trilinear weights across a boundary cell (section 16.5), so a boundary moves by up to half a
  cell: the kit's slab, whose boundary cell adds half a cell, comes out exact from +x (RMSE 0.0008)
  and half a cell too thick from -x (alpha 0.91 for 0.84, RMSE 0.051); on the smooth three-label
  field RMSE 0.030 to `reference` (0.017 at step 0.25), and 2.0 % of the pixels differ from it in
  coverage, alpha above 0.05 or not (0.9 % at step 0.25). The error grows with the share of
  boundary cells: 256 palette-coloured labels in rows one voxel wide (every cell a boundary)
  came out RMSE 0.14 from `reference`;
- VTK reads the label TFs' opacity as the opacity of one sample, with no correction for the sample
  distance, so they get the corrected opacity (`transfer.per_sample_functions`) and are rebuilt
  when the step changes. The main TF (label 0) is corrected by VTK as usual.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from volren.model.labels import LabelTransferFunction
from volren.model.settings import BlendMode, RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume
from volren.renderers.vtk_mappers._vtk import numpy_to_vtk, vtkImageData
from volren.renderers.vtk_mappers.transfer import per_sample_functions, scaled_tf, uniform_functions

#: VTK's label-map mask is an 8-bit texture.
MAX_VTK_LABEL = 255
#: What a hidden label (or a hidden label 0) draws with.
TRANSPARENT = TransferFunction1D.constant(0.0, (0.0, 0.0, 0.0))


def label_reason(volume: UniformVolume, settings: RenderSettings, mapper: str) -> str | None:
    """Why the vtk renderer cannot draw this label scene (the words after "vtk "), or None."""
    if mapper != "gpu":
        return f"draws label volumes only with its GPU ray cast mapper (label-map mask), not mapper {mapper}"
    if settings.blend_mode != BlendMode.COMPOSITE:
        return f"draws label volumes composite only, not with {settings.blend_mode}"
    if settings.shade:
        return "draws label volumes unshaded only (its label-map TFs are not checked with shading)"
    labels = volume.labels
    if labels is not None and labels.max_label > MAX_VTK_LABEL:
        return (
            f"draws labels up to {MAX_VTK_LABEL} only (VTK's label-map mask is 8-bit); "
            f"{volume.name!r} has labels up to {labels.max_label}"
        )
    return None


def label_mask(volume: UniformVolume) -> vtkImageData:
    """The label map as the uint8 vtkImageData that vtkGPUVolumeRayCastMapper.SetMaskInput takes."""
    assert volume.labels is not None
    image = vtkImageData()
    image.SetDimensions(*volume.dimensions)
    image.SetSpacing(*volume.spacing)
    image.SetOrigin(*volume.origin)
    values = np.ascontiguousarray(volume.labels.values.reshape(-1), dtype=np.uint8)
    array = numpy_to_vtk(values, deep=True)
    array.SetName("labels")
    image.GetPointData().SetScalars(array)
    return image


def set_label_functions(
    prop: Any,
    tf: LabelTransferFunction,
    present: tuple[int, ...],
    sample_distance: float,
    scale: float,
    data_lo: float,
    sentinel: float | None,
) -> None:
    """Give `prop` (a fresh vtkVolumeProperty) label 0's TF as its own and every other present
    label's TF as a label TF of per-sample opacity (module docstring); hidden labels transparent.
    `scale`, `data_lo` and `sentinel` are the scalars' as VTK gets them (`transfer`)."""
    main = tf.effective_tf(0) or TRANSPARENT
    color, opacity = uniform_functions(scaled_tf(main, scale), data_lo, sentinel)
    prop.SetColor(color)
    prop.SetScalarOpacity(opacity)
    prop.SetScalarOpacityUnitDistance(main.opacity_unit_distance)
    for label in present:
        if label == 0:
            continue
        own = tf.effective_tf(label) or TRANSPARENT
        color, opacity = per_sample_functions(scaled_tf(own, scale), sample_distance, data_lo, sentinel)
        prop.SetLabelColor(label, color)
        prop.SetLabelScalarOpacity(label, opacity)
