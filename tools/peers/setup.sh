#!/usr/bin/env bash
# Sets up the peers of tools/peers/run.py in two virtual environments (git-ignored): LuxCore 2.11
# (pyluxcore) in tools/peers/.venv-lux and Blender 5.0.1 as a module (bpy, with the system
# libraries it needs, by tools/gltf_scenes/setup.sh) in tools/peers/.venv-bpy. Both wheels are
# cp311: python3 must be 3.11. Mitsuba's references are tools/validate/refs (committed).
set -euo pipefail
here=$(dirname "$0")
python3 -m venv "$here/.venv-lux"
"$here/.venv-lux/bin/pip" install -q "pyluxcore==2.11" numpy
"$here/.venv-lux/bin/python" -c "import pyluxcore; print('pyluxcore', pyluxcore.Version())"
bash "$here/../gltf_scenes/setup.sh" "$here/.venv-bpy"
"$here/.venv-bpy/bin/pip" install -q numpy
