"""The app timing itself: the real `MainWindow` driven the way a person's hand drives it, and what
they would see measured (`volren bench app`; `python -m benchmarks.app_latency` builds on the same
driving). Qt is imported by the modules, not by this package.

- `drive`: the QApplication for a measurement, waiting in the event loop, input at 60 Hz.
- `gestures`: the gesture table (rotate, TF point, 2D widget, crop face) with the renderer `auto`
  picks, against the interaction targets.
"""
