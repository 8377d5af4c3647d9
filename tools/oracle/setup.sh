#!/usr/bin/env bash
# Set up the OpenCASCADE oracle: a Python venv (outside the repo) with OCP.
# Idempotent: reuses the venv and skips pip when the pinned version is there.
# Prints the venv's python path on the last line of stdout.
#
#   bash tools/oracle/setup.sh            # venv at $HOME/.cache/thinplan-venv
#   THINPLAN_VENV=/some/dir bash tools/oracle/setup.sh
#
# System libraries: the cadquery-ocp wheel bundles OCC's own libs, but
# OCP.cpython-*.so (and the VTK libs it pulls in) link against system
# libGL/libX11 and friends. On Debian 12 these come from:
#   libgl1 (-> libglx0, libglvnd0)  libx11-6 (-> libxcb1, libxau6, libxdmcp6,
#   libbsd0, libmd0)  libxrender1  libexpat1  zlib1g  libstdc++6  libgcc-s1
# They are installed (apt-get, root only) only if `import OCP` fails.
set -euo pipefail

VENV="${THINPLAN_VENV:-$HOME/.cache/thinplan-venv}"
OCP_PIN="cadquery-ocp==8.0.1.1.0"   # OCC 8.0.1
APT_PKGS="libgl1 libx11-6 libxrender1 libexpat1 zlib1g"
PY_CHECK='import OCP; from OCP.STEPControl import STEPControl_Reader; print(OCP.__version__)'

log() { echo "[oracle-setup] $*" >&2; }

if [ ! -x "$VENV/bin/python" ]; then
    log "creating venv at $VENV"
    mkdir -p "$(dirname "$VENV")"
    python3 -m venv "$VENV"
fi

want="${OCP_PIN#*==}"
have="$("$VENV/bin/python" -m pip show cadquery-ocp 2>/dev/null | sed -n 's/^Version: //p' || true)"
if [ "$have" != "$want" ]; then
    log "installing $OCP_PIN (have: ${have:-none})"
    "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check "$OCP_PIN" >&2
fi

if ! "$VENV/bin/python" -c "$PY_CHECK" >/dev/null 2>&1; then
    log "import OCP failed:"
    "$VENV/bin/python" -c "$PY_CHECK" >&2 || true
    if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null; then
        log "installing system libs: $APT_PKGS"
        apt-get update -qq >&2
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $APT_PKGS >&2
    else
        log "not root / no apt-get: install these system packages: $APT_PKGS"
    fi
    "$VENV/bin/python" -c "$PY_CHECK" >/dev/null
fi

log "OCP $("$VENV/bin/python" -c "$PY_CHECK") ready"
echo "$VENV/bin/python"
