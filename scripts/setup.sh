#!/usr/bin/env bash
# Set up volren on a Debian/Ubuntu machine; safe to run again (it only does what is missing).
#   1. system libraries for OpenGL through EGL (Mesa llvmpipe without a GPU), Qt and, for the
#      tests, a virtual X server;
#   2. a virtual environment in .venv with volren and the renderer plugins under plugins/ installed
#      in editable mode: `.[app,movie,zarr,cluster]` for the main job, `.[test,app,bench,movie,zarr,cluster]` with --tests, at the
#      versions CI tests (`-c constraints.txt`); re-installed when a pyproject.toml or
#      constraints.txt changes.
# Usage: scripts/setup.sh [--tests]
#   VOLREN_LATEST=1 scripts/setup.sh ...  ignores constraints.txt and upgrades every dependency to
#                                         its newest release (to test against them).
#   VOLREN_APT_LOCK_TIMEOUT=S ...         seconds to wait for another apt or dpkg to finish
#                                         before installing system packages (default 600).
set -euo pipefail
cd "$(dirname "$0")/.."

with_tests=0
[ "${1:-}" = "--tests" ] && with_tests=1

packages=(
  # OpenGL through EGL: without these VTK segfaults and moderngl cannot make a context
  libegl1 libgl1 libgl1-mesa-dri
  # X11/xcb and friends used by the VTK and Qt wheels
  libx11-6 libx11-xcb1 libxext6 libxkbcommon0 libxkbcommon-x11-0 libxcb1 libxcb-icccm4
  libxcb-image0 libxcb-keysyms1 libxcb-randr0 libxcb-render0 libxcb-render-util0 libxcb-shape0
  libxcb-shm0 libxcb-sync1 libxcb-util1 libxcb-xfixes0 libxcb-xinerama0 libxcb-xkb1
  libdbus-1-3 libfontconfig1 libfreetype6 libglib2.0-0
  # a C compiler for raycast's C march (volren/kernels/native.py; without one, numba's draws)
  gcc libc6-dev
)
if [ "$with_tests" = 1 ]; then
  packages+=(xvfb xauth)
fi

# Seconds to wait, in all, for the dpkg and apt locks another package manager holds (on a fresh
# machine's first boot, often unattended-upgrades or cloud-init) instead of failing at once.
apt_lock_left=${VOLREN_APT_LOCK_TIMEOUT:-600}

# Wait while another apt, dpkg or unattended-upgrades process runs, within the time left, saying so
# in one line (on stderr: apt's own output goes to /dev/null). apt's DPkg::Lock::Timeout (apt >=
# 1.9.11) covers the dpkg lock of `install`, but not on every apt release the lists lock of `update`.
wait_for_apt() {
  command -v pgrep >/dev/null 2>&1 || return 0
  local pids said=0
  while [ "$apt_lock_left" -gt 0 ] && pids=$(pgrep -d, -x 'apt|apt-get|aptitude|dpkg|unattended-upgr' 2>/dev/null); do
    [ "$said" = 1 ] || echo "setup: waiting up to ${apt_lock_left}s for another package manager (pid $pids) to release the apt/dpkg lock" >&2
    said=1
    sleep 1
    apt_lock_left=$((apt_lock_left - 1))
  done
}

# apt-get as root (through sudo where needed), non-interactive, waiting for the locks within the
# time left (then apt says who holds them); the environment goes through `env`, which sudo keeps.
apt_get() {
  wait_for_apt
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get -o "DPkg::Lock::Timeout=$apt_lock_left" "$@"
}

missing=()
if command -v dpkg-query >/dev/null 2>&1; then
  for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
fi
if [ "${#missing[@]}" -gt 0 ]; then
  echo "setup: installing system packages: ${missing[*]}"
  sudo=""
  [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1 && sudo="sudo"
  if command -v apt-get >/dev/null 2>&1; then
    apt_get update -qq
    apt_get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  else
    echo "setup: no apt-get here; please install the equivalents of: ${missing[*]}" >&2
  fi
fi

python=${PYTHON:-python3}
if ! "$python" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
  echo "setup: volren needs Python 3.11 or newer ($python is $("$python" --version 2>&1))" >&2
  exit 1
fi
if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv"
  "$python" -m venv .venv
fi
stamp=.venv/.volren-installed
if [ "${VOLREN_LATEST:-0}" = 1 ]; then
  pins=(--upgrade --upgrade-strategy eager)
  mode=latest
else
  pins=(-c constraints.txt)
  mode=pinned
fi
# "<hash of the pyproject files, constraints.txt and the mode> <extras>"
hash=$( { cat pyproject.toml plugins/*/pyproject.toml constraints.txt; echo "$mode"; } | sha256sum | cut -d' ' -f1)
installed=$(cat "$stamp" 2>/dev/null || true)
extras=$([ "$with_tests" = 1 ] && echo test,app,bench,movie,zarr,cluster || echo app,movie,zarr,cluster)
# the test install includes the app: the main job needs nothing more after it
if [ "${installed%% *}" != "$hash" ] || { [ "$extras" != app,movie,zarr,cluster ] && [ "${installed#* }" != "$extras" ]; }; then
  echo "setup: installing volren[$extras] and its dependencies into .venv ($mode versions)"
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q "${pins[@]}" -e ".[$extras]"
  for plugin in plugins/*/; do
    echo "setup: installing the renderer plugin $plugin"
    .venv/bin/python -m pip install -q --no-deps -e "$plugin"
  done
  echo "$hash $extras" > "$stamp"
fi

# Compile the renderers' kernels now rather than at the first frame (numba caches them on disk, and
# the C kernels' libraries are cached too; `volren prepare`), once per change of the sources: a fresh install's first `tetra` or `reference`
# frame otherwise waits 40-55 s. A renderer that cannot be prepared (no OpenGL) is reported, not fatal.
prepared=.venv/.volren-prepared
sources=$( { find volren plugins \( -name '*.py' -o -name '*.c' \) -not -path '*/tests/*' | LC_ALL=C sort | xargs cat; cat "$stamp"; } | sha256sum | cut -d' ' -f1)
if [ "$(cat "$prepared" 2>/dev/null || true)" != "$sources" ]; then
  echo "setup: compiling the renderers' kernels (volren prepare; once per change of the sources)"
  if .venv/bin/volren prepare; then
    echo "$sources" > "$prepared"
  else
    echo "setup: volren prepare failed; first frames will compile instead" >&2
  fi
fi
