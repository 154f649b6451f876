#!/usr/bin/env bash
# Set up (with the test extras and Xvfb) and run the whole test suite, a worker per core
# (pytest-xdist; a test file's tests stay on one worker, so its module fixtures are built once).
# Arguments go to pytest after these, so `-n 0` runs in one process.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh --tests
exec .venv/bin/python -m pytest -n auto --dist loadfile "$@"
