"""The transfer-function editors (Qt): the tabbed panel, undo and redo, the 1D editor (`one_d`)
and the 2D editor (`two_d`). Their Qt-free logic (histograms, colour-map presets, widget
geometry) lives in `volren.app.core`."""
