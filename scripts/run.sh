#!/usr/bin/env bash
# The main job: set up, then open the app where there is a display, else render the bundled
# samples offscreen with every registered renderer (PNGs in out/demo) and print the timings.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
if [ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ]; then
  exec .venv/bin/volren view "$@"
else
  exec .venv/bin/volren demo --out out/demo "$@"
fi
