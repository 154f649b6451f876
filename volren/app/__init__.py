"""The PyQt5 desktop app (`volren view`).

The modules are split so that everything which is not Qt-specific can be used and tested
without widgets, and so that later panels (the transfer-function editors) can plug into the same
state object the viewport observes:

- `state`: `ViewState`, the observable model of what is shown (volume, TF, camera, settings,
  renderer); no Qt.
- `interaction`: mouse gestures -> camera operations (VTK's trackball-camera style); no Qt.
- `imaging`: premultiplied float RGBA -> 8-bit RGB over a background colour; no Qt.
- `loading`: files -> a `LoadedInput` (volume, TF, camera, settings); no Qt.
- `renderer_choice`: which renderers can draw the loaded volume, and fallbacks; no Qt.
- `render_service`: the render worker thread that owns the renderer, newest request only.
- `scheduling`: turns state changes into reduced-size and full-quality frame requests.
- `load_task`: runs `loading` off the GUI thread.
- `viewport`, `renderer_box`, `dialogs`, `main_window`: the widgets.
- `main`: `run()`, what `volren view` calls.

Importing this package does not import Qt; the submodules that need it do.
"""
