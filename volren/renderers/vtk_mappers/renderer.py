"""VtkRenderer: VTK's volume mappers in an offscreen EGL window, read back as float RGBA.

Reproducibility: automatic sample-distance adjustment is off everywhere, the sample distance is
`settings.step` times the smallest voxel spacing, multisampling is off, and the camera is copied from
our `Camera` (position, focal point, view-up, angle or parallel scale, clipping range), so the
view and projection matrices are ours exactly. VTK's default headlight lights shaded volumes.

Uniform grids default to mapper `auto`: vtkSmartVolumeMapper's own policy (the GPU ray cast
mapper where the OpenGL context supports it, else the fixed-point ray caster) applied by us,
because vtkSmartVolumeMapper itself locks its GPU mapper's sample distance to the input spacing
and so ignores the requested step (measured: identical images at steps 1.0 and 0.0625; for
ironProt VTK samples far finer than half a voxel, for bonsai at half a voxel). `mapper=smart`
still gives the genuine vtkSmartVolumeMapper, at VTK's own step.

The framebuffer is 8 bits per channel: every output value is a multiple of 1/255.

Three mapper quirks are corrected here (measured on tetrahedralized boxes against the closed
form or `reference`): vtkUnstructuredGridVolumeRayCastMapper casts its rays through pixel corners,
so its window centre is moved by half a pixel to put them through pixel centres like every other
renderer (RMSE 0.015 -> 0.005); the same mapper loses rays that run inside a face plane (looking
along an axis of a lattice mesh, the pixels on the image diagonal lie in the cubes' diagonal
faces and came out up to 0.95 wrong: 19 pixels of 64x64), so its rays are moved a further
thousandth of a pixel, by different amounts along x and y (RAY_NUDGE_PX), off every such plane;
vtkOpenGLProjectedTetrahedraMapper draws its first frame wrong, so a new one renders a warm-up
frame first. The ray caster walks backwards across faces where a cell folds over its neighbour
(a tangled mesh), so it gets such cells detached (`convert.detached`).

Label volumes go to the GPU ray caster's label-map mask (`labels`); multi-channel volumes to a
vtkMultiVolume on it (`channels`). What they cannot draw (other mappers, blend modes, shading,
labels above 255, more than 10 channels) is refused in one line before VTK renders.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelTransferFunction
from volren.model.settings import BlendMode, RenderSettings
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import TetVolume, UniformVolume
from volren.renderers.base import (
    Accuracy,
    Capabilities,
    KindSupport,
    OptionSpec,
    ProgressCallback,
    QualityLevel,
    RendererBase,
)
from volren.renderers.opengl import require_opengl
from volren.renderers.vtk_mappers import _vtk
from volren.renderers.vtk_mappers.channels import ChannelVolumes, channel_reason, drawn_channels
from volren.renderers.vtk_mappers.convert import FINITE_NAME, image_data, set_camera, unstructured_grid
from volren.renderers.vtk_mappers.labels import label_mask, label_reason, set_label_functions
from volren.renderers.vtk_mappers.transfer import (
    masked_function,
    replace_nonfinite,
    scaled_tf,
    scaled_values,
    uniform_functions,
    unstructured_functions,
    vtk_scale,
)
from volren.vtk_messages import vtk_messages

#: The ray caster's rays are moved this far (pixels, x and y) off planes through pixel centres.
RAY_NUDGE_PX = (1e-3, 0.618e-3)

#: VTK's average-intensity blend draws every pixel opaque (alpha 1), not the contract's
#: (c(v) a(v), a(v)) of the mean value v, so `average` is not offered.
CONTRACT_BLEND_MODES = frozenset({BlendMode.COMPOSITE, BlendMode.MAXIMUM, BlendMode.MINIMUM})


def _smart(settings) -> Any:
    """The genuine smart mapper: VTK locks its sample distance to the data spacing."""
    mapper = _vtk.vtkSmartVolumeMapper()
    mapper.SetAutoAdjustSampleDistances(0)
    mapper.SetInteractiveAdjustSampleDistances(0)
    return mapper


def _gpu(settings) -> Any:
    mapper = _vtk.vtkOpenGLGPUVolumeRayCastMapper()
    mapper.SetAutoAdjustSampleDistances(0)
    return mapper


def _fixed_point(settings) -> Any:
    mapper = _vtk.vtkFixedPointVolumeRayCastMapper()
    mapper.SetAutoAdjustSampleDistances(0)
    mapper.SetLockSampleDistanceToInputSpacing(0)
    mapper.SetImageSampleDistance(1.0)
    return mapper


def _integrator(settings) -> Any:
    if settings.preintegration:
        return _vtk.vtkUnstructuredGridPreIntegration()
    return _vtk.vtkUnstructuredGridLinearRayIntegrator()


def _image_order_tet_mapper(cls: type, settings) -> Any:
    """A ray-casting unstructured mapper: one ray per pixel, our choice of ray integrator."""
    mapper = cls()
    mapper.SetAutoAdjustSampleDistances(0)
    mapper.SetImageSampleDistance(1.0)
    mapper.SetRayIntegrator(_integrator(settings))
    return mapper


def _ug_raycast(settings) -> Any:
    return _image_order_tet_mapper(_vtk.vtkUnstructuredGridVolumeRayCastMapper, settings)


def _ug_zsweep(settings) -> Any:
    return _image_order_tet_mapper(_vtk.vtkUnstructuredGridVolumeZSweepMapper, settings)


def _ug_projected(settings) -> Any:
    if settings.preintegration:
        raise VolrenError(
            "the vtk projected-tetrahedra mapper has no pre-integration; use mapper=raycast or zsweep"
        )
    return _vtk.vtkOpenGLProjectedTetrahedraMapper()


MapperFactory = Callable[[Any], Any]

#: mapper option value -> (volume kind, factory, blend modes it supports)
MAPPERS: dict[str, tuple[str, MapperFactory, frozenset[BlendMode]]] = {
    "auto": ("uniform", _gpu, CONTRACT_BLEND_MODES),  # resolved to gpu or fixed_point per context
    "smart": ("uniform", _smart, CONTRACT_BLEND_MODES),
    "gpu": ("uniform", _gpu, CONTRACT_BLEND_MODES),
    "fixed_point": (
        "uniform",
        _fixed_point,
        frozenset({BlendMode.COMPOSITE, BlendMode.MAXIMUM, BlendMode.MINIMUM}),
    ),
    "raycast": ("tet", _ug_raycast, frozenset({BlendMode.COMPOSITE})),
    "zsweep": ("tet", _ug_zsweep, frozenset({BlendMode.COMPOSITE})),
    "projected": ("tet", _ug_projected, frozenset({BlendMode.COMPOSITE})),
}
DEFAULT_MAPPER = {"uniform": "auto", "tet": "raycast"}
#: The mappers that sample at our step (the others step cell to cell, or choose their own).
STEPPED_MAPPERS = frozenset({"gpu", "fixed_point"})

_BLEND_SETTERS = {
    BlendMode.COMPOSITE: "SetBlendModeToComposite",
    BlendMode.MAXIMUM: "SetBlendModeToMaximumIntensity",
    BlendMode.MINIMUM: "SetBlendModeToMinimumIntensity",
}


def _clipping_planes(settings: RenderSettings) -> Any:
    """The clip region's half-spaces as VTK's planes: vtkPlane keeps the side its normal points
    to, as `ClipRegion` does; (a, b, c) is unit, so -d (a, b, c) lies on the plane."""
    planes = _vtk.vtkPlaneCollection()
    for a, b, c, d in settings.clip.half_spaces():
        plane = _vtk.vtkPlane()
        plane.SetNormal(a, b, c)
        plane.SetOrigin(-d * a, -d * b, -d * c)
        planes.AddItem(plane)
    return planes


class VtkRenderer(RendererBase):
    """VTK's volume mappers (smart mapper for grids, unstructured ray caster for tetrahedra)."""

    name: ClassVar[str] = "vtk"
    capabilities: ClassVar[Capabilities] = Capabilities(
        kinds={
            # kit (volren check-renderer vtk, llvmpipe): grids RMSE up to 0.068 (maximum projection),
            # 0.05 at step 1, the point 0.05 px off; meshes RMSE up to 0.02, the point 0.32 px off
            # the clip region goes to VTK's clipping planes (vtkPlaneCollection), which its volume
            # mappers for grids honour; its unstructured-grid mappers have none
            # labels: the GPU mapper's label-map mask, one label per sample (`labels`): kit slab RMSE
            # 0.0008 / 0.051 (+x / -x), three labels 0.030 to reference, silhouette off in 2 % of pixels.
            # channels: a vtkMultiVolume, extinctions multiplied out per step (`channels`): kit slab RMSE
            # 0.020, three channels 0.022 (independent components: 0.22 / 0.11). Both: GPU mapper only,
            # composite, unshaded; labels up to 255, at most 10 channels drawn (refused at render time)
            "uniform": KindSupport(
                shading=True,
                blend_modes=CONTRACT_BLEND_MODES,
                accuracy=Accuracy(rmse=0.07, position_px=0.1),
                clip_region=True,
                labels=True,
                channels=True,
            ),
            # VTK's unstructured-grid mappers draw wrong images from an eye inside the mesh's bounds
            # (measured on the kit's eye_inside scene, 0.025 allowed: RMSE 0.58 for the ray caster,
            # which draws nothing, 0.13 zsweep, 0.087 projected) and where a clipping plane cuts the
            # mesh (the kit's clip check: RMSE 0.40-0.43 near, 0.040 far), so such views are refused
            "tet": KindSupport(
                preintegration=True,
                accuracy=Accuracy(rmse=0.025, position_px=0.4),
                eye_inside=False,
                clipping=False,
            ),
        },
        quality=(
            QualityLevel("step 2", step=2.0),
            QualityLevel("step 1", step=1.0),
            QualityLevel("step 0.5 (default)", step=0.5),
            QualityLevel("step 0.25", step=0.25),
        ),
        backend="vtk",
        summary="VTK: vtkSmartVolumeMapper on grids, vtkUnstructuredGridVolumeRayCastMapper on tetrahedra",
    )
    options: ClassVar[tuple[OptionSpec, ...]] = (
        # None: the volume kind's default (DEFAULT_MAPPER)
        OptionSpec(
            "mapper",
            None,
            "choice",
            "uniform: auto (default: gpu where supported, else fixed_point), smart "
            "(VTK's own sample distance), gpu, fixed_point; tetrahedra: raycast (default), zsweep, projected",
            choices=tuple(MAPPERS),
        ),
    )

    def __init__(self) -> None:
        super().__init__()
        self._window: Any = None
        self._vtk_renderer: Any = None
        self._actor: Any = None
        self._property: Any = None
        self._dataset: Any = None
        self._dataset_detaches_folds = False
        self._sentinel: float | None = None
        self._scale = 1.0  # VTK gets the grid's values times this (transfer.vtk_scale)
        self._mapper: Any = None
        self._mapper_key: tuple | None = None
        self._tf_key: tuple | None = None
        self._needs_warmup = False
        self._auto_choice: str | None = None
        self._mask: Any = None  # the label map as VTK's mask (`labels`)
        self._channels = ChannelVolumes()
        self._shown: Any = None  # the prop in the VTK renderer: the volume, or the channels' multi-volume

    # ------------------------------------------------------------------------- hooks
    def _volume_changed(self) -> None:
        self._dataset = None
        self._mask = None
        self._mapper_key = None
        self._tf_key = None

    @property
    def _vol(self) -> UniformVolume | TetVolume:
        """The volume being drawn (`render` refuses a frame without one)."""
        assert isinstance(self._volume, UniformVolume | TetVolume)
        return self._volume

    def _mapper_used(self) -> str:
        """The name of the mapper made for the volume (`_ensure_mapper`)."""
        assert self._mapper_key is not None
        return str(self._mapper_key[0])

    def _labels(self) -> bool:
        """Whether this frame draws a label volume (a TF per label)."""
        return isinstance(self._tf, LabelTransferFunction)

    def mapper_name(self) -> str:
        """The VTK mapper this renderer uses for the current volume and options."""
        kind = self._volume.kind if self._volume is not None else "uniform"
        name = self.opts["mapper"] or DEFAULT_MAPPER[kind]
        if MAPPERS[name][0] != kind:
            valid = ", ".join(n for n, (k, _, _) in MAPPERS.items() if k == kind)
            raise VolrenError(f"vtk mapper {name!r} cannot draw {kind} volumes; choose one of {valid}")
        return name

    # ---------------------------------------------------------------------- pipeline
    def _ensure_window(self) -> None:
        if self._window is not None:
            return
        require_opengl()
        window = _vtk.vtkEGLRenderWindow() if _vtk.vtkEGLRenderWindow is not None else _vtk.vtkRenderWindow()
        window.SetOffScreenRendering(1)
        window.SetMultiSamples(0)
        window.SetAlphaBitPlanes(1)
        renderer = _vtk.vtkRenderer()
        renderer.SetBackground(0.0, 0.0, 0.0)
        renderer.SetBackgroundAlpha(0.0)
        window.AddRenderer(renderer)
        self._property = _vtk.vtkVolumeProperty()
        self._property.SetInterpolationTypeToLinear()
        self._property.IndependentComponentsOn()
        self._actor = _vtk.vtkVolume()
        self._actor.SetProperty(self._property)
        renderer.AddVolume(self._actor)
        self._window, self._vtk_renderer, self._shown = window, renderer, self._actor

    def _show(self, prop: Any) -> None:
        """Make `prop` the one volume the VTK renderer draws."""
        if self._shown is not prop:
            self._vtk_renderer.RemoveAllViewProps()
            self._vtk_renderer.AddVolume(prop)
            self._shown = prop

    def _new_property(self) -> None:
        """A fresh vtkVolumeProperty on the volume: label TFs, once set, cannot be taken back."""
        self._property = _vtk.vtkVolumeProperty()
        self._property.SetInterpolationTypeToLinear()
        self._property.IndependentComponentsOn()
        self._actor.SetProperty(self._property)
        self._tf_key = None

    def _walks_cells(self) -> bool:
        """Whether the mapper walks from cell to cell across shared faces (the unstructured ray caster)."""
        return self._vol.kind == "tet" and self.mapper_name() == "raycast"

    def _ensure_dataset(self) -> None:
        detach_folds = self._walks_cells()
        if self._dataset is not None and detach_folds == self._dataset_detaches_folds:
            return
        self._dataset_detaches_folds = detach_folds
        volume = self._volume
        if isinstance(volume, UniformVolume):
            self._scale = vtk_scale(volume.value_range)
            values = scaled_values(volume.values, self._scale)
            values, self._sentinel = replace_nonfinite(values, self._scalar_range())
            self._dataset = image_data(volume, values)
        else:
            assert isinstance(volume, TetVolume)
            self._sentinel = None  # cells with a non-finite corner are left out
            self._scale = 1.0
            self._dataset = unstructured_grid(volume, detach_folds)

    def _scalar_range(self) -> tuple[float, float]:
        """The finite data range in the units VTK gets."""
        lo, hi = self._vol.value_range
        return lo * self._scale, hi * self._scale

    def _resolve_auto(self) -> str:
        """vtkSmartVolumeMapper's choice: GPU ray casting if this context supports it."""
        if self._auto_choice is None:
            probe = _vtk.vtkOpenGLGPUVolumeRayCastMapper()
            supported = probe.IsRenderSupported(self._window, self._property)
            self._auto_choice = "gpu" if supported else "fixed_point"
        return self._auto_choice

    def _ensure_mapper(self) -> None:
        name = self.mapper_name()
        settings = self._settings
        if name == "auto":
            name = self._resolve_auto()
            # VTK's GPU ray caster cuts at whole samples (the kit's cut box: RMSE up to 0.070 at step
            # 0.5, against 0.052 uncut); the fixed-point mapper clips each ray to the planes
            # (0.022-0.029, below its uncut 0.025-0.030), so clipped scenes go to it (not label
            # volumes: only the GPU mapper has label maps)
            clipped = not settings.clip.is_empty and not self._labels()
            if clipped and settings.blend_mode in MAPPERS["fixed_point"][2]:
                name = "fixed_point"
        _, factory, blend_modes = MAPPERS[name]
        if settings.blend_mode not in blend_modes:
            raise VolrenError(f"vtk mapper {name!r} has no {settings.blend_mode} blend mode")
        # Only what is fixed when a mapper is made decides whether to make a new one: a new step
        # (cheap frames while dragging, a benchmark sweep) must not rebuild a mesh mapper.
        key = (name, settings.preintegration)
        if key != self._mapper_key:
            if self._mapper is not None:
                self._mapper.ReleaseGraphicsResources(self._window)
            self._mapper = factory(settings)
            self._mapper.SetInputData(self._dataset)
            self._actor.SetMapper(self._mapper)
            self._mapper_key = key
            self._needs_warmup = name == "projected"
        if name in STEPPED_MAPPERS:
            h = settings.step * self._vol.characteristic_length
            self._mapper.SetSampleDistance(h)
            if name == "fixed_point":
                self._mapper.SetInteractiveSampleDistance(h)
            else:
                self._mapper.SetUseJittering(int(settings.jitter))
        getattr(self._mapper, _BLEND_SETTERS[settings.blend_mode])()
        self._mapper.SetClippingPlanes(_clipping_planes(settings))
        if name == "gpu":
            self._ensure_mask()

    def _ensure_mask(self) -> None:
        """The GPU mapper's label-map mask: the volume's labels on a label frame, none otherwise."""
        if self._labels():
            if self._mask is None:
                self._mask = label_mask(self._volume)  # type: ignore[arg-type]
            if self._mapper.GetMaskInput() is not self._mask:
                self._mapper.SetMaskInput(self._mask)
            self._mapper.SetMaskTypeToLabelMap()
        elif self._mapper.GetMaskInput() is not None:
            self._mapper.SetMaskInput(None)

    def _masks_nonfinite(self) -> bool:
        """Whether this frame hides grid cells with a non-finite corner through the 2D TF over
        (value, finite) (see `transfer`): only VTK's GPU ray caster has 2D TFs, and only the
        composite blend reads them."""
        return (
            self._sentinel is not None
            and self._mapper_used() == "gpu"
            and self._settings.blend_mode is BlendMode.COMPOSITE
            and not self._labels()
        )

    def _ensure_label_property(self) -> None:
        """Label 0's TF as the property's own, each other label's as a label TF (`labels`)."""
        tf, volume = self._tf, self._volume
        assert isinstance(tf, LabelTransferFunction) and isinstance(volume, UniformVolume)
        assert volume.labels is not None
        h = self._settings.step * volume.characteristic_length
        key = ("labels", tf.state(), self._sentinel, self._scale, h)
        if key != self._tf_key:
            self._new_property()
            lo = self._scalar_range()[0]
            set_label_functions(self._property, tf, volume.labels.present, h, self._scale, lo, self._sentinel)
            self._tf_key = key

    def _ensure_tf_functions(self, masked: bool) -> None:
        """The property's colour and opacity functions (and the masked 2D TF) from the 1D TF."""
        tf, prop = self._tf, self._property
        assert isinstance(tf, TransferFunction1D)
        h = self._settings.step * self._vol.characteristic_length
        # The conversion depends on the volume kind, reset with it; the masked table on the step.
        key = (tf.version, self._sentinel, h if masked else None)
        if key != self._tf_key:
            build = unstructured_functions if self._vol.kind == "tet" else uniform_functions
            lo, hi = self._scalar_range()
            vtk_tf = scaled_tf(tf, self._scale)
            color, opacity = build(vtk_tf, lo, self._sentinel)
            prop.SetColor(color)
            prop.SetScalarOpacity(opacity)
            prop.SetScalarOpacityUnitDistance(tf.opacity_unit_distance)
            if masked:
                assert self._sentinel is not None
                prop.SetTransferFunction2D(masked_function(vtk_tf, (self._sentinel, hi), h))
            self._tf_key = key

    def _ensure_property(self) -> None:
        masked = self._masks_nonfinite()
        if self._labels():
            self._ensure_label_property()
        else:
            if self._property.GetNumberOfLabels():
                self._new_property()
            self._ensure_tf_functions(masked)
        settings, prop = self._settings, self._property
        if masked:
            prop.SetTransferFunctionModeTo2D()
            self._mapper.SetTransfer2DYAxisArray(FINITE_NAME)
        else:
            prop.SetTransferFunctionModeTo1D()
            if self._mapper_used() == "gpu":
                self._mapper.SetTransfer2DYAxisArray(None)
        prop.SetShade(int(settings.shade))
        prop.SetAmbient(settings.ambient)
        prop.SetDiffuse(settings.diffuse)
        prop.SetSpecular(settings.specular)
        prop.SetSpecularPower(settings.specular_power)

    def _apply_camera(self, camera: Camera) -> None:
        cam = self._vtk_renderer.GetActiveCamera()
        set_camera(cam, camera)
        if self._mapper_key is not None and self._mapper_key[0] == "raycast":
            width, height = self._window.GetSize()
            # Half a pixel (2 / size in window units) puts the rays through pixel centres; the
            # nudge keeps them out of face planes (module docstring).
            dx, dy = RAY_NUDGE_PX
            cam.SetWindowCenter((1.0 + 2.0 * dx) / width, (1.0 + 2.0 * dy) / height)
        else:
            cam.SetWindowCenter(0.0, 0.0)

    # ------------------------------------------------------------------------ render
    def _scene_reason(self) -> str | None:
        """Why VTK cannot draw this label or channel frame (`labels`, `channels`), or None."""
        tf = self._tf
        if not isinstance(tf, LabelTransferFunction | ChannelTransferFunction):
            return None
        name = self.mapper_name()
        if name == "auto":
            name = self._resolve_auto()
        if isinstance(tf, LabelTransferFunction):
            return label_reason(self._volume, self._settings, name)  # type: ignore[arg-type]
        return channel_reason(tf, self._settings, name)

    def _prepare_channels(self) -> Any:
        """Set up the channels' multi-volume for this frame; its mapper."""
        settings, volume = self._settings, self._volume
        assert isinstance(volume, UniformVolume) and isinstance(self._tf, ChannelTransferFunction)
        self._channels.update(volume, self._tf, self._window)
        mapper = self._channels.mapper
        mapper.SetSampleDistance(settings.step * volume.characteristic_length)
        mapper.SetUseJittering(int(settings.jitter))
        mapper.SetBlendModeToComposite()
        mapper.SetClippingPlanes(_clipping_planes(settings))
        self._show(self._channels.prop)
        return mapper

    def _prepare(self) -> tuple[Any, str]:
        """Set up the VTK pipeline for this frame; the mapper that draws it and its name."""
        if isinstance(self._tf, ChannelTransferFunction):
            return self._prepare_channels(), "gpu"
        self._ensure_dataset()
        self._ensure_mapper()
        self._ensure_property()
        self._show(self._actor)
        return self._mapper, self._mapper_used()

    def _render(
        self, camera: Camera, width: int, height: int, progress: ProgressCallback | None
    ) -> tuple[NDArray[np.float32], Mapping[str, float]]:
        self._ensure_window()
        reason = self._scene_reason()
        if reason:
            raise VolrenError(f"renderer {self.name} {reason}")
        if isinstance(self._tf, ChannelTransferFunction) and not drawn_channels(self._tf):
            if progress is not None:
                progress(1.0)
            return np.zeros((height, width, 4), np.float32), {}
        mapper, mapper_name = self._prepare()
        self._window.SetSize(width, height)
        self._apply_camera(camera)
        pixels = _vtk.vtkUnsignedCharArray()
        with vtk_messages() as messages:
            if self._needs_warmup:
                self._window.Render()
                self._needs_warmup = False
            self._window.Render()
            self._window.GetRGBACharPixelData(0, 0, width - 1, height - 1, 0, pixels)
        if messages.errors:
            raise VolrenError(f"VTK failed to render: {messages.errors[0].text[:300]}")
        if pixels.GetNumberOfTuples() != width * height:
            raise VolrenError(
                f"VTK returned {pixels.GetNumberOfTuples()} pixels for a {width}x{height} frame"
            )
        rgba = _vtk.vtk_to_numpy(pixels).reshape(height, width, 4)[::-1]
        image = rgba.astype(np.float32) / np.float32(255.0)
        # Rounding each 8-bit channel on its own can leave colour one step above alpha, which no
        # premultiplied image may hold (found by `volren bench stress` on tetrahedra).
        np.minimum(image[..., :3], image[..., 3:], out=image[..., :3])
        if progress is not None:
            progress(1.0)
        counters: dict[str, float] = {}
        if mapper_name in STEPPED_MAPPERS:
            counters["sample_distance"] = mapper.GetSampleDistance()
        return np.ascontiguousarray(image), counters

    def release(self) -> None:
        if self._window is not None:
            if self._mapper is not None:
                self._mapper.ReleaseGraphicsResources(self._window)
            self._channels.release(self._window)
            self._window.Finalize()
        self._window = self._vtk_renderer = self._actor = self._property = None
        self._mapper = self._dataset = self._mask = self._shown = None
        super().release()
