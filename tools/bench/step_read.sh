#!/usr/bin/env bash
# Read + B-rep build throughput of thinplan's STEP reader against OpenCASCADE,
# on the same files, in one run (ratios hold on a noisy machine; absolute
# numbers do not). Usage: bash tools/bench/step_read.sh [RUNS]
set -euo pipefail
cd "$(dirname "$0")/../.."
RUNS="${1:-5}"
DATA="${THINPLAN_DATA:-../shared/data}"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/thinplan-target}"
cargo build -q --release -p thinplan-step --example read_bench
bash tools/oracle/setup.sh >/dev/null
PY="$HOME/.cache/thinplan-venv/bin/python"
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
for set in mfcad aagnet; do
  echo "== $set: thinplan (median-free total over $RUNS runs)"
  "$CARGO_TARGET_DIR/release/examples/read_bench" "$DATA/$set" "$RUNS"
  echo "== $set: OpenCASCADE (sum of per-file medians of $RUNS runs)"
  "$PY" tools/oracle/occ_inspect.py "$DATA/$set" --time "$RUNS" --out /tmp/thinplan-occ-times-$set.json >/dev/null
  "$PY" - "$set" <<'PYEOF'
import json, sys
d = json.load(open(f"/tmp/thinplan-occ-times-{sys.argv[1]}.json"))
t = d["_meta"]["timing"]
print(json.dumps(t, sort_keys=True))
PYEOF
done
