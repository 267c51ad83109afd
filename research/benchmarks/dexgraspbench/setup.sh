#!/usr/bin/env bash
# One-time setup of DexGraspBench (DGB) for `mani-lab eval dexgraspbench`: checks DGB's work tree and builds its own
# venv. Nothing here is a dependency of the product; both folders live outside the repository.
#
#   research/benchmarks/dexgraspbench/setup.sh DGB_SRC DGB_VENV
#
# DGB_SRC: a work tree of github.com/JYChen18/DexGraspBench at commit 1e7a5a6 WITH its Menagerie submodule
#          (git clone ...; git -C DGB_SRC checkout 1e7a5a6; git -C DGB_SRC submodule update --init), or the same
#          files placed by hand (README.md beside this script).
# DGB_VENV: where to build DGB's venv (Python 3.10-3.11; DGB pins mujoco 3.3.2).
set -euo pipefail
SRC=${1:?usage: setup.sh DGB_SRC DGB_VENV}
VENV=${2:?usage: setup.sh DGB_SRC DGB_VENV}
HERE=$(cd "$(dirname "$0")" && pwd)
PY=${PYTHON:-python3}

for f in src/task/eval_func/fc_mocap.py assets/hand/leap/right_hand.xml assets/hand/allegro/right_hand.xml \
         assets/hand/shadow/right_hand.xml third_party/mujoco_menagerie/wonik_allegro/assets \
         third_party/mujoco_menagerie/shadow_hand/assets; do
  [ -e "$SRC/$f" ] || { echo "missing $SRC/$f (DGB's tree with its Menagerie submodule: see README.md)"; exit 2; }
done
if [ ! -e "$SRC/third_party/mujoco_menagerie/leap_hand/right_hand.xml" ]; then
  echo "no Menagerie leap_hand/right_hand.xml: writing the fallback (README.md)"
  "$PY" "$HERE/leap_menagerie_fallback.py" "$SRC"
fi

"$PY" -m venv "$VENV"
# DGB's README list (its pins where it has them), without CUDA: torch 2.13.0 is the CPU wheel on local disk here
# (any other version pulls CUDA wheels); DGB's `task` package imports all of these when it loads
"$VENV/bin/pip" install torch==2.13.0
"$VENV/bin/pip" install numpy==1.26.4 mujoco==3.3.2 trimesh hydra-core transforms3d scipy matplotlib scikit-learn \
  usd-core imageio 'qpsolvers[clarabel]'
"$VENV/bin/python" -c "import sys; sys.path.insert(0, '$SRC/src'); import task.eval_func.fc_mocap, mujoco; \
print('DGB ready, mujoco', mujoco.__version__)"
echo "export DGB_SRC=$SRC DGB_PYTHON=$VENV/bin/python"
