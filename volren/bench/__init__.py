"""Measuring renderers: error metrics against `reference`, cached reference images, benchmarks."""
