#!/usr/bin/env bash
# Build the formation_ros documentation (Sphinx, MyST Markdown) into HTML.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${FORMATION_VENV:-$ROOT/.venv}"
OUT="$ROOT/build/docs"
PYTHON_EXE=""

usage() {
  cat <<USAGE
Usage: scripts/build_docs.sh [--out DIR] [--venv DIR] [--python EXE]

Sets up the virtual environment if needed (scripts/setup_env.sh: Sphinx, myst-parser and the
Read the Docs theme come with it) and builds docs/ into HTML with warnings as errors: a broken
reference, a page missing from the table of contents or a parameter without a description
fails the build. The parameter, topic, command-line and benchmark tables are generated from
the code and from docs/bench/*.json while it builds. Needs no network. Open DIR/index.html.

Options:
  --out DIR      where to write the HTML (default: build/docs)
  --venv DIR     virtual environment (default: \$FORMATION_VENV or .venv)
  --python EXE   build with this interpreter as it is (no set-up), e.g. the tests' own
  -h, --help     show this help
USAGE
}

while [[ $# -gt 0 ]]; do
  case "$1" in
    --out) OUT="${2:?--out needs a directory}"; shift 2 ;;
    --venv) VENV="${2:?--venv needs a directory}"; shift 2 ;;
    --python) PYTHON_EXE="${2:?--python needs an interpreter}"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "build_docs.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done

if [[ -z "$PYTHON_EXE" ]]; then
  bash "$ROOT/scripts/setup_env.sh" --venv "$VENV"
  PYTHON_EXE="$VENV/bin/python"
fi
export MPLBACKEND="${MPLBACKEND:-Agg}"
"$PYTHON_EXE" -m sphinx -W -n --keep-going -q -b html -d "$OUT/.doctrees" "$ROOT/docs" "$OUT"
echo "build_docs.sh: open $OUT/index.html"
