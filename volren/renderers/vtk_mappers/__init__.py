"""The `vtk` renderer: VTK's volume mappers driven offscreen, drawing DESIGN.md's optical model.

Uniform grids go through vtkSmartVolumeMapper (or, by option, the GPU ray cast or fixed-point
mapper); tetrahedral meshes through vtkUnstructuredGridVolumeRayCastMapper (or projected
tetrahedra, or ZSweep). See `transfer.py` for how our transfer function is mapped onto VTK's
conventions, which differ for the unstructured mappers.
"""
