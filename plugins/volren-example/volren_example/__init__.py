"""volren-example: a renderer plugin for volren, written only against volren's public contract."""

from volren_example.renderer import ExampleRenderer

__all__ = ["ExampleRenderer"]
