#!/usr/bin/env bash
# Run the whole formation_ros test suite in the project's virtual environment.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${FORMATION_VENV:-$ROOT/.venv}"

usage() {
  cat <<USAGE
Usage: scripts/run_tests.sh [--venv DIR] [-- PYTEST_ARGS...]

Sets up the virtual environment if needed (scripts/setup_env.sh), then runs every test under
test/ with pytest: the numpy core, the simulator, the style checks and the ROS 2 integration
tests. Each run uses its own ROS_DOMAIN_ID with discovery kept on this host.

Options:
  --venv DIR   virtual environment to use (default: \$FORMATION_VENV or .venv)
  --           pass the remaining arguments to pytest (e.g. -- -k jump -x)
  -h, --help   show this help
USAGE
}

pytest_args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --venv) VENV="${2:?--venv needs a directory}"; shift 2 ;;
    --) shift; pytest_args=("$@"); break ;;
    -h|--help) usage; exit 0 ;;
    *) echo "run_tests.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done

bash "$ROOT/scripts/setup_env.sh" --venv "$VENV"
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export MPLBACKEND=Agg
cd "$ROOT"
exec "$VENV/bin/python" -m pytest test -p no:cacheprovider ${pytest_args[@]+"${pytest_args[@]}"}
