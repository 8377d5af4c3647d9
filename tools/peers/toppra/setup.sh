#!/usr/bin/env bash
# TOPP-RA peer for the feed schedule (crates/feeds): installs a pinned toppra into the shared
# project venv (outside the repo). Idempotent: skips pip when the pinned version is there.
# Prints the venv's python path on the last line of stdout.
#
#   bash tools/peers/toppra/setup.sh          # venv at $HOME/.cache/thinplan-venv
#   THINPLAN_VENV=/some/dir bash tools/peers/toppra/setup.sh
#
# toppra 0.6.10 ships manylinux wheels (it pulls numpy, scipy, matplotlib); licence MIT.
set -euo pipefail

VENV="${THINPLAN_VENV:-$HOME/.cache/thinplan-venv}"
PIN="toppra==0.6.10"

log() { echo "[toppra-setup] $*" >&2; }

if [ ! -x "$VENV/bin/python" ]; then
    log "creating venv at $VENV"
    mkdir -p "$(dirname "$VENV")"
    python3 -m venv "$VENV"
fi

want="${PIN#*==}"
have="$("$VENV/bin/python" -m pip show toppra 2>/dev/null | sed -n 's/^Version: //p' || true)"
if [ "$have" != "$want" ]; then
    log "installing $PIN (have: ${have:-none})"
    "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check "$PIN" >&2
fi

"$VENV/bin/python" -c 'import toppra, toppra.algorithm, toppra.constraint' >&2
log "ok: toppra $want in $VENV"
echo "$VENV/bin/python"
