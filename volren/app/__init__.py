"""The PyQt5 desktop app (`volren view`), grouped by concept.

Everything that is not Qt-specific sits in `core`, usable and tested without widgets; the widgets
around it all observe and edit one `core.state.ViewState`. Importing this package does not import
Qt, nor does importing anything in `core` (pyproject.toml's import contracts, tests/test_import_rules.py);
the other subpackages do.

- `main`: `run()`, what `volren view` calls (window, input, event loop or --screenshot); Qt inside.
- `core/` (Qt-free):
  - `state`: `ViewState`, the observable model of what is shown (volume, TF, camera, settings,
    renderer, background, crop).
  - `interaction`: mouse gestures -> camera operations (VTK's trackball-camera style).
  - `frame_sizes`: how big preview frames are (a quarter of the pixels, fewer for slow renderers).
  - `loading`: files -> a `LoadedInput` (volume, TF, camera, settings) and back to a `Scene`.
  - `renderer_choice`: which renderers can draw the loaded volume, and fallbacks.
  - `picking`: the point a pixel shows, with its value and gradient magnitude.
  - `joint_histogram`: the value x gradient-magnitude histogram behind the 2D TF editor.
  - `colormap_presets`: the 1D editor's colour maps, read from `colormap_presets.json` (curated)
    and `paraview_colormaps.json` (ParaView's, for the colour-map browser).
  - `tf_widget_geometry`: outlines, handles, moves and resizes of the 2D editor's widgets.
  - `tf_seeding`: the 2D TF a 1D TF becomes when the 2D editor is switched on.
  - `preview_settings`: which renderer and settings draw the previews while dragging.
  - `view_directions`: the cameras of the view-direction buttons (+X ... -Z, as ParaView's).
  - `overlay_geometry`: where the viewport's outline and orientation axes fall on screen.
  - `crop_handles`: the crop box's face handles on screen, which one a pixel hits, the box a
    drag makes.
  - `label_picking`: the first visible label along a pixel's ray (Ctrl+click with labels drawn).
- `rendering/` (Qt):
  - `render_service`: the render worker thread that owns the renderer, newest request only.
  - `scheduling`: state changes -> reduced-size and full-quality frame requests.
  - `viewport`: the widget that shows frames and turns mouse input into camera changes.
  - `overlays`: the outline, orientation axes and colour legend painted over the frames.
  - `renderer_chooser`: the renderer combo box, with why a renderer is disabled.
- `files/` (Qt):
  - `load_task`: runs `core.loading` off the GUI thread, cancellable.
  - `screenshot`: renders a screenshot at a chosen size off the GUI thread and writes the PNG.
  - `recent_files`: File > Open Recent, kept in QSettings.
  - `screenshot_dialog`: the Save Screenshot dialog.
  - `background_job`: runs a job that writes a file (screenshot, movie) in a pool thread, with
    progress and cancel.
  - `movie_export`: records an orbit of the view into MP4 or GIF off the GUI thread.
  - `movie_dialog`: the Export Movie dialog.
  - `series_steps`: a time series' steps read off the GUI thread, neighbours ahead, a few kept.
  - `level_refiner`: an OME-Zarr image's finer levels read in the background after the coarsest.
  - `raw_dialog`: the layout of a headerless raw file (shape, type, byte order, spacing).
- `tf_editor/` (Qt):
  - `panel`: the TF dock, the 1D and 2D editors in tabs.
  - `history`: undo and redo of TF edits, recorded from the state.
  - `one_d/editor`: the 1D editor panel (presets, range, files) around the two canvases below.
  - `one_d/point_canvas`: the base of the two canvases below: control points on a value axis.
  - `one_d/opacity_curve`: the opacity curve over the value histogram.
  - `one_d/color_bar`: the colour bar with its colour stops.
  - `one_d/point_entry`: typed value and opacity of the selected point.
  - `one_d/color_entry`: typed value and picked colour of the selected colour stop.
  - `one_d/preset_browser`: the searchable colour-map browser, a swatch per map.
  - `two_d/editor`: the 2D editor panel (add and delete widgets, colour, opacity, gradient axis).
  - `two_d/widget_canvas`: the widgets drawn and dragged over the joint histogram.
- `panels/` (Qt): the settings panels (lighting, sampling, blend mode, crop box, background,
  dataset facts) and their shared base and controls; `labels`, the Labels panel: a row per label
  of a segmentation (show, colour, name, opacity, solo; the selected label's TF is the one the 1D
  editor edits); `channels`, the Channels panel: a row per channel of a multi-channel volume
  (show, colour, name, weight; the selected channel's TF is the one the 1D editor edits).
- `window/` (Qt):
  - `main_window`: `MainWindow`, which builds the parts below and wires them to the state,
    viewport, render thread, menus, toolbar and status bar.
  - `file_actions`: File > Open, Open DICOM folder, Open Recent, loading in the background.
  - `scene_actions`: File > Save Scene.
  - `label_actions`: File > Open Labels and Close Labels (a segmentation read in the background).
  - `screenshot_actions`: File > Save Screenshot.
  - `movie_actions`: File > Export Movie.
  - `time_control`: the time bar of a time series (slider, step label, Play).
  - `job_progress`: the progress dialog of a screenshot or movie, with Cancel.
  - `renderer_control`: the renderer in use: chooser, fallbacks, the frame label.
  - `file_drops`: files dropped on the window open like File > Open.
  - `docks`: places the TF editors and settings panels, and Ctrl+click picking (a 2D TF widget,
    or with labels drawn the label seen there).
  - `quality_control`: the Quality box (the measured settings of each level).
- `timing/` (Qt): the app timing itself for `volren bench app`:
  - `drive`: the QApplication of a measurement, waiting in its event loop, input at 60 Hz.
  - `gestures`: the gesture table (rotate, TF point, 2D widget, crop face) against the targets.
"""
