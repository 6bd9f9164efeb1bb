#!/usr/bin/env bash
# Sets up everything `make demo`, `make test` and `make bench` need on a fresh
# Debian machine: Debian packages (when run as root), then .venv with the
# project and its test tools. Safe to run again: it only installs what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

# python3-venv: Debian's interpreter and its venv module (below).
DEB_PACKAGES=(espeak-ng libespeak-ng1 chromium fonts-noto-cjk sox redis-server python3-venv)
missing=()
for pkg in "${DEB_PACKAGES[@]}"; do
  dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
done
if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" = 0 ]; then
    echo "setup: installing Debian packages: ${missing[*]}" >&2
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  else
    echo "setup: please install these Debian packages (needs root): ${missing[*]}" >&2
  fi
fi

# The interpreter: Debian's python3 when it is 3.11 or newer, else the first python3 on PATH
# (PYTHON=... chooses another). Debian builds it with profile-guided and link-time optimisation; an
# interpreter built without them (pyenv's default build, this machine kind's python3) runs
# `cartoonface generate` with ~4 % more CPU (0.95x the wall) and pure-Python loops ~1.4x slower
# (docs/BENCHMARKS.md, "The interpreter").
if [ -z "${PYTHON:-}" ]; then
  PYTHON=python3
  if /usr/bin/python3 -c 'import sys, venv; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
    PYTHON=/usr/bin/python3
  fi
fi
if [ ! -x .venv/bin/python ]; then
  "$PYTHON" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip
# A .venv made before the photo extra switched to opencv-contrib-python holds
# opencv-python-headless: remove it first so that only one package provides cv2.
if .venv/bin/python -m pip show -q opencv-python-headless >/dev/null 2>&1; then
  .venv/bin/python -m pip uninstall -q -y opencv-python-headless
fi
.venv/bin/python -m pip install -q -e ".[dev,photo]"
# Our modules' bytecode written now: a shell with PYTHONDONTWRITEBYTECODE set (as ours) would
# otherwise compile ~100 modules again at every command's start (~0.12 s; docs/BENCHMARKS.md, "Start-up").
.venv/bin/python -m compileall -q cartoonface
