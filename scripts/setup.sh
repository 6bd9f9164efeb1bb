#!/usr/bin/env bash
# Sets up everything `make demo`, `make test` and `make bench` need on a fresh
# Debian machine: Debian packages (when run as root), then .venv with the
# project and its test tools. Safe to run again: it only installs what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

DEB_PACKAGES=(espeak-ng libespeak-ng1 chromium fonts-noto-cjk)
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

PYTHON=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  "$PYTHON" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -e ".[dev,photo]"
# Face from a photo (docs/photo.md): mediapipe 0.10.14 ships its face models in the wheel;
# installed without its requirements, which pin packages the photo extra replaces.
.venv/bin/python -m pip install -q --no-deps "mediapipe==0.10.14"
