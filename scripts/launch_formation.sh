#!/usr/bin/env bash
# Start a whole formation: runs the Python launcher (formation_ros/tools/launcher.py) with an
# interpreter that can import the installed package. Options: see --help.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

prefix="${FORMATION_PREFIX:-}"
args=("$@")
for ((k = 0; k + 1 < ${#args[@]}; k++)); do
  [[ "${args[k]}" == --prefix ]] && prefix="${args[k + 1]}"
done

python=(python3)
if [[ -n "$prefix" ]] || ! command -v ros2 >/dev/null 2>&1 \
   || ! ros2 pkg prefix formation_ros >/dev/null 2>&1; then
  if [[ -z "$prefix" ]]; then
    IFS=: read -r -a candidates <<<"${AMENT_PREFIX_PATH:-}"
    for dir in "${candidates[@]}" "$ROOT/install/formation_ros" "$ROOT/install"; do
      if [[ -x "$dir/lib/formation_ros/plant" ]]; then prefix="$dir"; break; fi
    done
  fi
  sites=("$ROOT")  # nothing installed: the launcher from the source tree says so
  if [[ -n "$prefix" && -x "$prefix/lib/formation_ros/plant" ]]; then
    read -r shebang <"$prefix/lib/formation_ros/plant"
    read -r -a python <<<"${shebang#\#!}"
    sites=("$prefix"/lib/python3*/site-packages)
    export FORMATION_PREFIX="$prefix"
  fi
  PYTHONPATH="$(IFS=:; echo "${sites[*]}")${PYTHONPATH:+:$PYTHONPATH}"
  export PYTHONPATH
fi
exec "${python[@]}" -m "${FORMATION_LAUNCHER_MODULE:-formation_ros.tools.launcher}" "$@"
