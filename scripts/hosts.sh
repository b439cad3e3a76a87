#!/usr/bin/env bash
# Run a formation across hosts made of network namespaces on this computer (root only): runs
# formation_ros/tools/hosts.py with the interpreter the launcher uses. Options: see --help.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export FORMATION_LAUNCHER_MODULE=formation_ros.tools.hosts
exec bash "$ROOT/scripts/launch_formation.sh" "$@"
