#!/usr/bin/env bash
# Set everything up, build with colcon and run the demo formation as a real multi-process system.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${FORMATION_VENV:-$ROOT/.venv}"
PARAMS="$ROOT/config/paper_section5.yaml"
DURATION=28
OUT=""

usage() {
  cat <<USAGE
Usage: scripts/demo.sh [--params FILE] [--duration S] [--out DIR] [--venv DIR]

Sets up the virtual environment (scripts/setup_env.sh), builds the package with colcon into
install/, and runs the demo formation with scripts/launch_formation.sh: the plant, the
reference node and one process per robot talking over DDS, recorded into a rosbag2. At the
end formation_report reads the bag and prints the metrics summary; the run directory holds
the bag (bag/), metrics.json, the figures, trajectory.npz and plant_stats.json.

Options:
  --params FILE  parameters file (default: config/paper_section5.yaml, the paper's Section 5)
  --duration S   wall-clock seconds to run, start-up included (default: $DURATION)
  --out DIR      run directory (default: runs/demo-<date>-<time>)
  --venv DIR     virtual environment (default: \$FORMATION_VENV or .venv)
  -h, --help     show this help
USAGE
}

while [[ $# -gt 0 ]]; do
  case "$1" in
    --params) PARAMS="${2:?--params needs a file}"; shift 2 ;;
    --duration) DURATION="${2:?--duration needs seconds}"; shift 2 ;;
    --out) OUT="${2:?--out needs a directory}"; shift 2 ;;
    --venv) VENV="${2:?--venv needs a directory}"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "demo.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done
if [[ ! -f "$PARAMS" ]]; then
  echo "demo.sh: parameters file '$PARAMS' not found" >&2
  exit 2
fi
OUT="${OUT:-$ROOT/runs/demo-$(date +%Y%m%d-%H%M%S)}"

bash "$ROOT/scripts/setup_env.sh" --venv "$VENV"
mkdir -p "$ROOT/log"
echo "demo.sh: colcon build (install space: $ROOT/install)"
(cd "$ROOT" && "$VENV/bin/python" -m colcon --log-base "$ROOT/log" build \
   --base-paths "$ROOT" --build-base "$ROOT/build" --install-base "$ROOT/install" \
   > "$ROOT/log/colcon_build.txt" 2>&1) || {
  echo "demo.sh: colcon build failed; see $ROOT/log/colcon_build.txt" >&2; exit 1; }
export ROS_AUTOMATIC_DISCOVERY_RANGE="${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}"
PATH="$VENV/bin:$PATH" bash "$ROOT/scripts/launch_formation.sh" "$PARAMS" \
  --duration "$DURATION" --out "$OUT" --record "$OUT/bag"
echo
echo "demo: run directory: $OUT"
echo "demo:   bag (rosbag2, MCAP): $OUT/bag"
echo "demo:   figures: $(cd "$OUT" && ls ./*.png | tr '\n' ' ')"
echo "demo:   metrics: $OUT/metrics.json"
