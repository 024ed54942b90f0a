#!/bin/bash
# Cold `tmpnav plan` of each scenario with an older checkout and with this one, in turn, each
# from a fresh cache: the wall time, the objective and the stage times (one line a run).
#   git worktree add -f /tmp/wbase 879ecd6
#   benchmarks/ab_plan.sh /tmp/wbase scenario.yaml ...
set -u
base=$1; shift
here=$(cd "$(dirname "$0")/.." && pwd)
for f in "$@"; do
  for tree in base main; do
    if [ "$tree" = base ]; then dir=$base; else dir=$here; fi
    cache=$(mktemp -d)
    start=$(date +%s.%N)
    out=$(cd "$dir" && PYTHONPATH="$dir" "$here/.venv/bin/python" -m tmpnav plan "$f" --cache-dir "$cache" 2>&1)
    code=$?
    end=$(date +%s.%N)
    rm -rf "$cache"
    stages=$(echo "$out" | grep -A1 "time \[s\]" | tail -1)
    objective=$(echo "$out" | grep -oE "objective [a-z]+ \([^)]*\): [0-9.]+" | head -1 | grep -oE "[0-9.]+$")
    printf "%s %s exit=%s wall=%.2f objective=%s | %s\n" "$(basename "$f" .yaml)" "$tree" "$code" \
      "$(echo "$end - $start" | bc)" "$objective" "$stages"
  done
done
