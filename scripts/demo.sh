#!/usr/bin/env bash
# Set everything up and run the demo formation: the paper's Section 5 with figures and metrics.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${FORMATION_VENV:-$ROOT/.venv}"
PARAMS="$ROOT/config/paper_section5.yaml"
OUT=""

usage() {
  cat <<USAGE
Usage: scripts/demo.sh [--params FILE] [--out DIR] [--venv DIR]

Sets up the virtual environment (scripts/setup_env.sh), runs the demo formation with
formation_sim and prints where the figures and metrics.json are, with a metrics summary.

Options:
  --params FILE  parameters file (default: config/paper_section5.yaml)
  --out DIR      output directory (default: runs/demo-<date>-<time>)
  --venv DIR     virtual environment (default: \$FORMATION_VENV or .venv)
  -h, --help     show this help
USAGE
}

while [[ $# -gt 0 ]]; do
  case "$1" in
    --params) PARAMS="${2:?--params needs a file}"; shift 2 ;;
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
"$VENV/bin/formation_sim" "$PARAMS" --out "$OUT"
echo
echo "demo: figures: $(cd "$OUT" && ls ./*.png | tr '\n' ' ')"
echo "demo: metrics: $OUT/metrics.json"
