#!/usr/bin/env bash
# Sets up Blender as a Python module (bpy from PyPI) in a virtual environment (default
# tools/gltf_scenes/.venv, git-ignored; the first argument overrides) for
# tools/gltf_scenes/make_scenes.py. bpy 5.0.1 ships cp311 wheels only: python3 must be 3.11.
set -euo pipefail
venv=${1:-$(dirname "$0")/.venv}

# bpy's __init__.so links against X11/GL system libraries that the wheel does not bundle
# (`import bpy` fails with "libXi.so.6: cannot open shared object file" etc. without them).
# Run as root (the project's machines and CI are), this installs any of Debian's packages
# for them that are missing; otherwise it only says which are missing.
pkgs=(libx11-6 libxext6 libxi6 libxxf86vm1 libxfixes3 libxrender1 libxkbcommon0 libsm6 libxt6
      libgl1 libopengl0)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  if [[ $(id -u) == 0 ]]; then
    apt-get update -q
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q "${missing[@]}"
  else
    echo "setup: missing system packages (apt-get install as root): ${missing[*]}" >&2
  fi
fi

python3 -m venv "$venv"
"$venv/bin/pip" install -q "bpy==5.0.1"
"$venv/bin/python" -c "import bpy; print('bpy', bpy.app.version_string)"
