"""Experiments and report tooling behind the docs: not installed, run from a source checkout.

- `preint`: pre-integration tables, seconds and error per table size (docs/preintegration-benchmark.md);
- `slicer_table`: slicer and vtk against reference per sample step (docs/slicer-benchmark.md);
- `vtk_vs_reference`: VTK's error and time on the shared scenes (docs/vtk-vs-reference-512.md);
- `gpu`: the OpenGL renderers on a machine with a GPU (gpu.md for BENCHMARKS.md);
- `report`: `volren bench run|skip|stress|app` into one folder, then BENCHMARKS.md.

Run them as ``python -m benchmarks.NAME --help`` from the repository root. The shared datasets are
found with --shared or $VOLREN_SHARED. What users run stays in the package (`volren bench ...`).
"""
