#!/usr/bin/env bash
# A refactoring must not change a program: plans every bundled sample with the
# working tree and with REV (default HEAD) and compares the G-code, tool table
# and plan bytes. Exit 0 when all are identical, 1 with the differing files
# named. Release builds; REV is built in a worktree under $HOME/.cache with its
# own target directory so the two builds do not evict each other.
# Usage: bash tools/same_gcode.sh [REV]
set -euo pipefail
cd "$(dirname "$0")/.."
REV=${1:-HEAD}
CACHE=${THINPLAN_SAME_CACHE:-$HOME/.cache/thinplan-same}
mkdir -p "$CACHE"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/thinplan-target}"
cargo build --release --locked --bin thinplan >/dev/null
NEW="$CARGO_TARGET_DIR/release/thinplan"

sha=$(git rev-parse "$REV")
WT="$CACHE/worktree"
git worktree remove --force "$WT" >/dev/null 2>&1 || rm -rf "$WT"
git worktree prune
git worktree add --detach "$WT" "$sha" >/dev/null
(cd "$WT" && CARGO_TARGET_DIR="$CACHE/target" cargo build --release --locked --bin thinplan >/dev/null)
OLD="$CACHE/target/release/thinplan"

run() {
  local bin=$1 dir=$2 name
  rm -rf "$dir" && mkdir -p "$dir"
  for name in $("$NEW" samples); do
    name=${name#builtin:}
    # Exit codes 0 (safe) and 8 (incomplete) both write a program; the
    # comparison covers whatever was written, so any code is recorded.
    set +e
    "$bin" plan "builtin:$name" --out "$dir/$name.plan.json" \
      --gcode "$dir/$name.ngc" --tool-table "$dir/$name.tbl" >/dev/null 2>&1
    echo "$?" > "$dir/$name.rc"
    set -e
  done
}
run "$OLD" "$CACHE/old"
run "$NEW" "$CACHE/new"
if diff -rq "$CACHE/old" "$CACHE/new"; then
  echo "identical: $(ls "$CACHE/new"/*.ngc | wc -l) programs, plans and tool tables ($sha vs working tree)"
else
  exit 1
fi
