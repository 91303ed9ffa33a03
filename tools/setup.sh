#!/usr/bin/env bash
# Install everything rvmsim needs on a fresh Debian machine with Python 3.11:
#   - Debian packages for headless OpenGL (EGL on Mesa's llvmpipe; OSMesa as a fallback),
#   - the rvmsim package itself with its Python dependencies (and the test and docs extras
#     with --test),
#   - Chromium (headless: `rvmsim signoff` prints its PDF with it; the browser tests use it).
# Safe to run again: packages already present are not fetched twice.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
extras=""
if [[ "${1:-}" == "--test" ]]; then extras="[test,docs]"; fi

apt_pkgs=(libegl1 libegl-mesa0 libgl1-mesa-dri libgles2 libosmesa6)
# Headless Chromium: the sign-off's PDF (Playwright drives it; no browser download).
if ! command -v chromium >/dev/null 2>&1; then apt_pkgs+=(chromium); fi
missing=()
for p in "${apt_pkgs[@]}"; do
    dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if (( ${#missing[@]} )); then
    sudo_cmd=""
    if [[ "$(id -u)" != 0 ]]; then sudo_cmd="sudo"; fi
    echo "setup: installing Debian packages: ${missing[*]}"
    $sudo_cmd apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${missing[@]}" >/dev/null
fi

python3 -m pip install -q --disable-pip-version-check -e "${here}${extras}"
echo "setup: done"
