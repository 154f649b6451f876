"""The volume file formats volren reads, and how a path is matched to one of them."""

from __future__ import annotations

from pathlib import Path

from volren.errors import file_error
from volren.io.formats.base import FileFormat, Grid, Inspection
from volren.io.formats.dicom import DICOM, has_dicom_magic
from volren.io.formats.metaimage import METAIMAGE
from volren.io.formats.nifti import NIFTI
from volren.io.formats.nrrd import NRRD
from volren.io.formats.slc import SLC
from volren.io.formats.vtk_legacy import LEGACY
from volren.io.formats.vtk_xml import VTI, VTU

FORMATS: tuple[FileFormat, ...] = (VTI, LEGACY, VTU, NRRD, METAIMAGE, NIFTI, SLC, DICOM)

#: For messages: every suffix, plus the two things that are not suffixes.
SUPPORTED = (
    ", ".join(s for f in FORMATS for s in f.suffixes) + ", a DICOM folder, .raw (or any file with shape=)"
)


def suffix_of(path: Path) -> str:
    """The lower-case suffix, with '.nii.gz' kept whole."""
    name = path.name.lower()
    return ".nii.gz" if name.endswith(".nii.gz") else path.suffix.lower()


def find_format(path: Path) -> FileFormat | None:
    """The format of an existing, non-empty file or folder; None for headerless raw ('.raw')."""
    if path.is_dir():
        return DICOM
    suffix = suffix_of(path)
    for fmt in FORMATS:
        if suffix in fmt.suffixes:
            return fmt
    if suffix == ".raw":
        return None
    if has_dicom_magic(path):
        return DICOM
    raise file_error(path, f"unknown volume format {suffix or '(no suffix)'!r}; volren reads {SUPPORTED}")


__all__ = ["FORMATS", "SUPPORTED", "FileFormat", "Grid", "Inspection", "find_format", "suffix_of"]
