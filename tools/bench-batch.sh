#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Batch throughput (docs/datasets.md, Throughput): 200 randomized scenes of examples/python/
# random-drops.json (2-3 objects from 4 shapes at random sizes and materials, 2 s each), warm
# bank cache, rendered with 1 and then 2 local Dask workers; prints renders/s of each run.
# Usage: bash tools/bench-batch.sh [BUILD_DIR (default build/ci)] [WORK_DIR (default a temp dir)]
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "${1:-$repo/build/ci}" && pwd)"
work="${2:-$(mktemp -d)}"
export PYTHONPATH="$build/python"
mkdir -p "$work"
cp "$repo/examples/python/random-drops.json" "$work/"
echo '{"id": "r", "random": "random-drops.json", "seed": 1, "count": 200}' > "$work/bench.jsonl"
cd "$work"
echo "bench-batch: warming the bank cache in $work/cache"
/usr/bin/python3 -m strike batch bench.jsonl -o warm --workers 2 --cache cache --quiet
for workers in 1 2; do
  rm -rf "out$workers"
  /usr/bin/python3 -m strike batch bench.jsonl -o "out$workers" --workers "$workers" --cache cache 2>&1 | tail -1
done
cmp <(cat out1/*.wav) <(cat out2/*.wav) && echo "bench-batch: 1- and 2-worker outputs identical"
# Per render inside the 1-worker process (each ID.json's timings_s): on a shared machine the
# renders/s above move with the neighbours' load, these medians less so.
/usr/bin/python3 - <<'PY'
import glob, json, statistics
timings = [json.load(open(f))["timings_s"] for f in glob.glob("out1/*.json")]
med = {k: 1000 * statistics.median(t[k] for t in timings) for k in ("job", "total", "simulate", "modes", "synthesize")}
print("bench-batch: 1 worker, median per render: job %.1f ms (engine %.1f: simulate %.1f, banks %.1f, synthesize %.1f)"
      % (med["job"], med["total"], med["simulate"], med["modes"], med["synthesize"]))
PY
echo "bench-batch: $(uptime)"
