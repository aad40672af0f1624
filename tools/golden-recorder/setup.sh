#!/usr/bin/env bash
# A virtual environment with SocNavGym 0.1.1 as the golden episodes were recorded with it
# (docs/spec.md 10.1), for the DSRNN configs: torch and DGL are not installed (record.py
# stubs them; the DSRNN reward never calls the SNGNN model). Needs Python 3.11, a C++ compiler and
# network access to the package index. Usage: tools/golden-recorder/setup.sh [VENV_DIR] (default .venv-socnavgym)
set -euo pipefail
venv=${1:-.venv-socnavgym}
python3 -m venv "$venv"
"$venv/bin/pip" install --quiet "numpy<2" gym==0.26.2 opencv-python-headless matplotlib "shapely>=2,<3" \
    Cython pyyaml cmake setuptools wheel threadpoolctl
# RVO2's Python bindings build from source against the venv's Cython and CMake.
PATH="$venv/bin:$PATH" CMAKE_POLICY_VERSION_MINIMUM=3.5 \
    "$venv/bin/pip" install --quiet --no-build-isolation pyrvo2-danieldugas==0.0.2
"$venv/bin/pip" install --quiet --no-deps socnavgym==0.1.1
echo "ready: $venv/bin/python tools/golden-recorder/record.py --help"
