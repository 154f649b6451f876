"""Frames for the viewport: the render thread, when to render and at what cost, the viewport
widget and the renderer chooser (Qt)."""
