#!/usr/bin/env bash
# Planning time per generated corpus part, import to G-code with stage 9's
# verification, against `builtin:wing_rib` in the same run (the ratio holds
# on a loaded machine where seconds do not). Release build.
# Usage: bash tools/bench/corpus.sh [CORPUS_DIR] [TIMEOUT_S]   (default
# $THINPLAN_CORPUS or $HOME/.cache/thinplan-corpus, 300 s per part).
# Prints a Markdown table: part, seconds, ratio to the wing rib, exit code,
# verdict, operations, operations the verification removed.
set -euo pipefail
cd "$(dirname "$0")/../.."
C=${1:-${THINPLAN_CORPUS:-$HOME/.cache/thinplan-corpus}}
T=${2:-300}
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/thinplan-target}"
cargo build --release --locked --bin thinplan >/dev/null 2>&1
B="$CARGO_TARGET_DIR/release/thinplan"
W=$(mktemp -d)
one() {
  local part=$1 name=$2 s e rc
  s=$(date +%s.%N)
  set +e
  timeout "$T" "$B" plan "$part" --json --out "$W/$name.plan.json" --gcode "$W/$name.ngc" \
    --tool-table "$W/$name.tbl" > "$W/$name.json" 2>/dev/null
  rc=$?
  set -e
  e=$(date +%s.%N)
  python3 - "$W/$name.json" "$name" "$rc" "$(echo "$e - $s" | bc)" <<'PY'
import json, sys
path, name, rc, t = sys.argv[1:5]
try:
    r = json.load(open(path))
except Exception:
    r = {}
v = r.get('verification') or {}
print(f"{name}\t{float(t):.1f}\t{rc}\t{r.get('verdict')}\t{len(r.get('operation_order', []))}\t{len(v.get('removed', []))}")
PY
}
ref=$(one builtin:wing_rib wing_rib_builtin)
ref_t=$(echo "$ref" | cut -f2)
echo "| part | s | × wing_rib | exit | verdict | operations | removed |"
echo "| --- | ---: | ---: | ---: | --- | ---: | ---: |"
echo "$ref" | awk -F'\t' -v r="$ref_t" '{printf "| %s | %s | %.2f | %s | %s | %s | %s |\n", $1, $2, $2/r, $3, $4, $5, $6}'
for f in "$C"/*.step; do
  n=$(basename "$f" .step)
  one "$f" "$n" | awk -F'\t' -v r="$ref_t" '{printf "| %s | %s | %.2f | %s | %s | %s | %s |\n", $1, $2, $2/r, $3, $4, $5, $6}'
done
rm -rf "$W"
