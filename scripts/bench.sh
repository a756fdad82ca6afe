#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds the Google Benchmark micro-benchmarks (Release, own build directory, no -march=native: the
# library dispatches SSE2 / AVX2+FMA at run time) and runs them with the flags BENCHMARKS.md quotes.
# Extra arguments go to envpis_bench (e.g. --benchmark_filter=Product). JSON lands in $BUILD/bench.json.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build-bench}
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release -DENVPIS_BUILD_TESTS=OFF -DENVPIS_BUILD_APPS=OFF
cmake --build "$BUILD" -j2 --target envpis_bench
"$BUILD/bench/envpis_bench" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
  --benchmark_out="$BUILD/bench.json" --benchmark_out_format=json "$@"
