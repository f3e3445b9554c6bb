#!/usr/bin/env bash
# make bench: Google Benchmark of full steps; results also in bench/results.json.
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/$build/bench/phymul_bench" --benchmark_out="$root/bench/results.json" \
  --benchmark_out_format=json --benchmark_counters_tabular=true
"$root/$build/bench/phymul_interaction_bench" \
  --benchmark_out="$root/bench/results_interactions.json" --benchmark_out_format=json \
  --benchmark_counters_tabular=true
