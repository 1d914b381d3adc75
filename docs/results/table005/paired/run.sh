#!/bin/bash
# The same benches at two code versions at once, one worker and one thread each, so that both see the same
# machine: Table I's seed 0 on HouseExpo, DungeonMaps and the ROS maps (3 robots) and on the seven smaller
# KTH floors (8 robots), every strategy, at 0.05 m.
#
#   bash docs/results/table005/paired/run.sh OLD_CHECKOUT NEW_CHECKOUT OUT_DIR
#
# STRATEGIES=a,b,... runs those strategies alone (default: all seven).
#
# Each checkout is a worktree of this repository at the version to time, with ../shared beside it; both
# run with this checkout's .venv and their own src. Writes OUT_DIR/{before,after}_{dev3,kth7}/.
set -euo pipefail
old=$(realpath "$1")
new=$(realpath "$2")
mkdir -p "$3"
out=$(realpath "$3")
python="$(cd "$(dirname "$0")/../../../../.venv/bin" && pwd)/python"  # not realpath: the venv's python is a link
all="${STRATEGIES:-hier,hier-heuristic,utility,nearest,coscan,ncm,oracle}"

run() {  # checkout, tag
  cd "$1"
  local K=../shared/maps/kth_floorplans
  MREXPLORE_THREADS=1 PYTHONPATH=src "$python" -m mrexplore bench \
    --maps ../shared/maps/houseexpo ../shared/maps/dungeon ../shared/maps/ros --strategies "$all" --robots 3 \
    --seeds 1 --resolution 0.05 --workers 1 --max-steps 60000 --no-baseline-bytes --no-progress --out "$out/$2_dev3"
  MREXPLORE_THREADS=1 PYTHONPATH=src "$python" -m mrexplore bench \
    --maps $K/50052748.yaml $K/50052749.yaml $K/50052750.yaml $K/50052751.yaml $K/50052752.yaml $K/50052753.yaml \
    $K/50052754.yaml --strategies "$all" --robots 8 --seeds 1 --resolution 0.05 --workers 1 --max-steps 100000 \
    --no-baseline-bytes --no-progress --out "$out/$2_kth7"
}

run "$old" before &
run "$new" after &
wait
