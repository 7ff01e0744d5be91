#!/usr/bin/env bash
# Sets up Mitsuba 3 from PyPI in a virtual environment (default tools/validate/.venv, git-ignored)
# for tools/validate/run.py. The llvm_ad_rgb variant (much faster) needs Debian's libllvm19;
# without it run.py falls back to scalar_rgb.
set -euo pipefail
venv=${1:-$(dirname "$0")/.venv}
python3 -m venv "$venv"
"$venv/bin/pip" install -q "mitsuba==3.9.1" numpy
if ! ldconfig -p | grep -q libLLVM; then
  echo "setup: libllvm19 not found; 'apt-get install libllvm19' for the llvm_ad_rgb variant" >&2
fi
"$venv/bin/python" -c "import mitsuba; print('mitsuba', mitsuba.__version__)"
