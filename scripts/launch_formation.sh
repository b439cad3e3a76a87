#!/usr/bin/env bash
# Start a whole formation: the plant, the reference node and one robot process per robot.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

usage() {
  cat <<USAGE
Usage: scripts/launch_formation.sh PARAMS.yaml [--duration S] [--out DIR] [--record DIR]
                                   [--prefix DIR]

Starts the plant, the reference node and N robot nodes (N = num_robots in PARAMS.yaml), robot i
in namespace /robot_<i>, all with the same parameters file, the reference node on the plant's
simulated time (/clock). Output lines are prefixed with the node's name. Stops every
process it started when the duration ends, on Ctrl-C or on SIGTERM (then still writes the
report of --out / --record), and when any node exits on its own (then with a non-zero exit
code).

Options:
  --duration S   wall-clock seconds to run; 0 runs until Ctrl-C
                 (default: 'duration' in PARAMS.yaml divided by plant.realtime_factor)
  --out DIR      run directory: the plant writes trajectory.npz and plant_stats.json there,
                 PARAMS.yaml is copied there, and formation_report writes metrics.json and the
                 figures there at the end (the directory must not exist yet, or be empty)
  --record DIR   record every formation topic into a rosbag2 directory DIR (metadata.yaml +
                 MCAP; DIR must not exist yet), started before the other nodes and stopped
                 after them; at the end formation_report reads the bag and writes
                 metrics.json and the figures (into --out if given, else into DIR)
  --prefix DIR   install space of formation_ros (default: found from 'ros2', AMENT_PREFIX_PATH
                 or ./install/formation_ros)
  -h, --help     show this help

Executables: 'ros2 run formation_ros <exe>' where the ros2 command knows the package, else
<prefix>/lib/formation_ros/<exe> with the install's Python path set, as 'ros2 run' would.
USAGE
}

die() { echo "launch_formation.sh: $*" >&2; exit 2; }

PARAMS=""
DURATION=""
OUT=""
RECORD=""
PREFIX="${FORMATION_PREFIX:-}"
while [[ $# -gt 0 ]]; do
  case "$1" in
    --duration) DURATION="${2:?--duration needs seconds}"; shift 2 ;;
    --out) OUT="${2:?--out needs a directory}"; shift 2 ;;
    --record) RECORD="${2:?--record needs a directory}"; shift 2 ;;
    --prefix) PREFIX="${2:?--prefix needs a directory}"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    -*) die "unknown option '$1' (see --help)" ;;
    *) [[ -z "$PARAMS" ]] || die "only one parameters file, got '$PARAMS' and '$1'"
       PARAMS="$1"; shift ;;
  esac
done
[[ -n "$PARAMS" ]] || { usage >&2; exit 2; }
[[ -f "$PARAMS" ]] || die "parameters file '$PARAMS' not found"
PARAMS="$(cd "$(dirname "$PARAMS")" && pwd)/$(basename "$PARAMS")"
if [[ -n "$DURATION" ]] && ! [[ "$DURATION" =~ ^[0-9]+([.][0-9]+)?$ ]]; then
  die "--duration must be a number of seconds >= 0, got '$DURATION'"
fi

if [[ -n "$OUT" ]]; then
  if [[ -d "$OUT" ]] && [[ -n "$(ls -A "$OUT")" ]]; then
    die "--out directory '$OUT' is not empty; choose a new one"
  fi
  mkdir -p "$OUT"
  OUT="$(cd "$OUT" && pwd)"
fi
if [[ -n "$RECORD" ]]; then
  if [[ -e "$RECORD" ]] && ! { [[ -d "$RECORD" ]] && [[ -z "$(ls -A "$RECORD")" ]]; }; then
    die "--record directory '$RECORD' exists already; choose a new one"
  fi
  [[ -d "$RECORD" ]] && rmdir "$RECORD"
  mkdir -p "$(dirname "$RECORD")"
  RECORD="$(cd "$(dirname "$RECORD")" && pwd)/$(basename "$RECORD")"
fi

find_prefix() {
  local dir
  for dir in $(tr ':' ' ' <<<"${AMENT_PREFIX_PATH:-}") "$ROOT/install/formation_ros" \
             "$ROOT/install"; do
    if [[ -x "$dir/lib/formation_ros/plant" ]]; then echo "$dir"; return 0; fi
  done
  return 1
}

USE_ROS2=0
if [[ -z "$PREFIX" ]] && command -v ros2 >/dev/null 2>&1 \
   && ros2 pkg prefix formation_ros >/dev/null 2>&1; then
  USE_ROS2=1
else
  [[ -n "$PREFIX" ]] || PREFIX="$(find_prefix)" || die "formation_ros is not installed: build it
  with 'colcon build' (see README) or pass --prefix INSTALL_DIR"
  [[ -x "$PREFIX/lib/formation_ros/plant" ]] || die "no $PREFIX/lib/formation_ros/plant"
  for site in "$PREFIX"/lib/python3*/site-packages; do
    [[ -d "$site" ]] && export PYTHONPATH="$site${PYTHONPATH:+:$PYTHONPATH}"
  done
  export AMENT_PREFIX_PATH="$PREFIX${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
fi

exe() {
  if [[ $USE_ROS2 -eq 1 ]]; then echo "ros2 run formation_ros $1"; else
    echo "$PREFIX/lib/formation_ros/$1"; fi
}

# shellcheck disable=SC2046
CHECK="$($(exe formation_sim) "$PARAMS" --check)" || die "invalid parameters (see above)"
read -r NUM_ROBOTS WALL_MS <<<"$CHECK"
if [[ -n "$DURATION" ]]; then
  WALL_MS="$(awk -v s="$DURATION" 'BEGIN { printf "%d", s * 1000 }')"
fi

[[ -n "$OUT" ]] && cp "$PARAMS" "$OUT/params.yaml"

PIDS=()
NAMES=()
STOPPING=0
RECORDER_PID=""

start() {
  local name="$1"; shift
  # shellcheck disable=SC2046
  setsid $(exe "$1") "${@:2}" > >(sed -u "s/^/[$name] /") 2>&1 &
  PIDS+=("$!")
  NAMES+=("$name")
}

stop_group() {
  local pid deadline
  for pid in "$@"; do
    kill -INT -- "-$pid" 2>/dev/null || kill -INT "$pid" 2>/dev/null || true
  done
  deadline=$((SECONDS + 10))
  for pid in "$@"; do
    while kill -0 "$pid" 2>/dev/null && [[ $SECONDS -lt $deadline ]]; do sleep 0.1; done
    if kill -0 "$pid" 2>/dev/null; then
      echo "launch_formation.sh: process $pid did not stop; killing it" >&2
      kill -KILL -- "-$pid" 2>/dev/null || kill -KILL "$pid" 2>/dev/null || true
    fi
  done
}

stop_all() {
  [[ $STOPPING -eq 1 ]] && return 0
  STOPPING=1
  local pid others=()
  for pid in "${PIDS[@]}"; do [[ "$pid" != "$RECORDER_PID" ]] && others+=("$pid"); done
  [[ ${#others[@]} -gt 0 ]] && stop_group "${others[@]}"
  [[ -n "$RECORDER_PID" ]] && stop_group "$RECORDER_PID"
  wait 2>/dev/null || true
}

INTERRUPTED=""
on_signal() {
  INTERRUPTED="$1"
  if [[ ${#PIDS[@]} -eq 0 ]]; then exit 0; fi
}
trap 'on_signal SIGINT' INT
trap 'on_signal SIGTERM' TERM
trap 'stop_all' EXIT

PLANT_ARGS=(--ros-args --params-file "$PARAMS")
[[ -n "$OUT" ]] && PLANT_ARGS+=(-p "plant.output_dir:=$OUT")
[[ -n "$RECORD" ]] && PLANT_ARGS+=(-p "plant.wait_for_subscribers:=2")
echo "launch_formation.sh: $NUM_ROBOTS robots from $PARAMS" \
     "($( [[ $USE_ROS2 -eq 1 ]] && echo 'ros2 run' || echo "$PREFIX"))," \
     "$( [[ "$WALL_MS" == 0 ]] && echo 'until Ctrl-C' || echo "for $((WALL_MS / 1000)) s")"
if [[ -n "$RECORD" ]]; then
  start record record --ros-args --params-file "$PARAMS" -p "record.path:=$RECORD"
  RECORDER_PID="${PIDS[-1]}"
  for ((k = 0; k < 150; k++)); do
    [[ -d "$RECORD" ]] || ! kill -0 "$RECORDER_PID" 2>/dev/null && break
    sleep 0.1
  done
  [[ -d "$RECORD" ]] || die "the recorder did not start (see its output above)"
fi
start plant plant "${PLANT_ARGS[@]}"
start reference reference --ros-args --params-file "$PARAMS" -p use_sim_time:=true
for ((i = 1; i <= NUM_ROBOTS; i++)); do
  start "robot_$i" robot --ros-args -r "__ns:=/robot_$i" -p "robot_id:=$i" \
    --params-file "$PARAMS" \
    -p "wait_for_subscribers:=$([[ -n "$RECORD" ]] && echo 2 || echo 1)"
done

now_ms() { echo $(( $(date +%s%N) / 1000000 )); }
failed=""
end_ms=$(( $(now_ms) + WALL_MS ))
while :; do
  for i in "${!PIDS[@]}"; do
    if ! kill -0 "${PIDS[$i]}" 2>/dev/null; then
      code=0; wait "${PIDS[$i]}" || code=$?
      failed="${NAMES[$i]} exited early with code $code"
      break 2
    fi
  done
  if [[ -n "$INTERRUPTED" ]] || { [[ "$WALL_MS" != 0 ]] && [[ $(now_ms) -ge $end_ms ]]; }; then
    break
  fi
  sleep 0.5 & wait $! || true
done
[[ -n "$INTERRUPTED" ]] && echo "launch_formation.sh: stopping ($INTERRUPTED)" >&2
trap - INT TERM
stop_all
if [[ -n "$failed" ]]; then
  echo "launch_formation.sh: $failed; stopped the others" >&2
  exit 1
fi
if [[ -n "$RECORD" ]]; then
  $(exe formation_report) "$RECORD" --out "${OUT:-$RECORD}"
elif [[ -n "$OUT" ]]; then
  if [[ -f "$OUT/trajectory.npz" ]]; then
    $(exe formation_report) "$OUT" --out "$OUT"
  else
    echo "launch_formation.sh: the plant wrote no trajectory to $OUT" >&2
    exit 1
  fi
fi
