#!/usr/bin/env bash
# Run the whole formation_ros test suite in the project's virtual environment.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${FORMATION_VENV:-$ROOT/.venv}"

usage() {
  cat <<USAGE
Usage: scripts/run_tests.sh [--venv DIR] [--workers N] [-- PYTEST_ARGS...]

Sets up the virtual environment if needed (scripts/setup_env.sh), then runs every test under
test/ with pytest: the numpy core, the simulator, the style checks and the ROS 2 integration
tests, in N worker processes (pytest-xdist). Each worker talks DDS on a ROS_DOMAIN_ID of its
own with discovery kept on this host and builds its own colcon install space; the multi-host
tests run one after another on one worker. The 15 slowest tests are listed at the end.

Options:
  --venv DIR    virtual environment to use (default: \$FORMATION_VENV or .venv)
  --workers N   test workers (default: \$FORMATION_TEST_WORKERS or 2, one per core of the
                2-core machine; 0 runs everything in this process, one test at a time)
  --            pass the remaining arguments to pytest (e.g. -- -k jump -x); test files or
                folders among them are run instead of the whole of test/ (e.g. --
                test/core/test_jump.py)
  -h, --help    show this help
USAGE
}

WORKERS="${FORMATION_TEST_WORKERS:-2}"
pytest_args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --venv) VENV="${2:?--venv needs a directory}"; shift 2 ;;
    --workers) WORKERS="${2:?--workers needs a number}"; shift 2 ;;
    --) shift; pytest_args=("$@"); break ;;
    -h|--help) usage; exit 0 ;;
    *) echo "run_tests.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done

if ! [[ "$WORKERS" =~ ^[0-9]+$ ]]; then
  echo "run_tests.sh: --workers takes a whole number, got '$WORKERS'" >&2
  exit 2
fi

bash "$ROOT/scripts/setup_env.sh" --venv "$VENV"
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export MPLBACKEND=Agg
cd "$ROOT"
parallel=()
if [[ "$WORKERS" -gt 0 ]]; then
  parallel=(-n "$WORKERS" --dist loadgroup)
fi
targets=(test)
for arg in ${pytest_args[@]+"${pytest_args[@]}"}; do
  if [[ "$arg" != -* && -e "${arg%%::*}" ]]; then
    targets=()
    break
  fi
done
exec "$VENV/bin/python" -m pytest ${targets[@]+"${targets[@]}"} -p no:cacheprovider \
  --durations=15 ${parallel[@]+"${parallel[@]}"} ${pytest_args[@]+"${pytest_args[@]}"}
