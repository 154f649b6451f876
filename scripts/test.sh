#!/usr/bin/env bash
# Set up (with the test extras and Xvfb) and run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh --tests
exec .venv/bin/python -m pytest "$@"
