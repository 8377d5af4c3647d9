#!/usr/bin/env bash
# Prints the path of a Python that has OpenCASCADE's binding (OCP) for generate.py.
# Delegates to the shared checkers' setup (idempotent: creates/reuses a venv outside
# the repo with cadquery-ocp, numpy, scipy). Progress goes to stderr, the python path
# is the last line of stdout.
#
#   PY=$(bash tools/corpus/setup.sh) && $PY tools/corpus/generate.py OUT_DIR --check
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
SHARED="${THINPLAN_SHARED:-$REPO/../shared}"
SETUP="$SHARED/tools/setup.sh"
[ -f "$SETUP" ] || SETUP=/work/shared/tools/setup.sh
if [ ! -f "$SETUP" ]; then
    echo "tools/corpus/setup.sh: no shared setup script (set THINPLAN_SHARED)" >&2
    exit 1
fi
PY="$(bash "$SETUP" | tail -n 1)"
"$PY" -c 'import OCP' >&2
echo "$PY"
