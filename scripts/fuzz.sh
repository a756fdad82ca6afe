#!/usr/bin/env bash
# Builds the libFuzzer targets of fuzz/ (clang, ASan + UBSan, library instrumented too) in build-fuzz
# and runs each for a bounded time, starting from a copy of its seed corpus in a temporary directory
# (new inputs never land in the repository). Fails if any target finds a crash, a sanitizer report, a
# leak or a contract violation; the reproducers are kept in build-fuzz/fuzz-artifacts/<target>/.
#
# Usage: bash scripts/fuzz.sh
# Environment:
#   FUZZ_SECONDS   seconds per target (default 60)
#   FUZZ_GLTF_SECONDS  seconds of mutation for fuzz_gltf after its seed replay (default: two thirds of
#                  FUZZ_SECONDS, so that replay + mutation end with the other targets; 0: replay only)
#   FUZZ_TARGETS   space-separated targets (default: fuzz_image_load fuzz_table_product fuzz_gltf)
#   FUZZ_PARALLEL  1 (default): run the targets at the same time (one per core); 0: one after another
#   FUZZ_BUILD     build directory (default build-fuzz)
#   FUZZ_SEED      libFuzzer's -seed (default 1: CI explores the same inputs on the same code and a
#                  failure replays); 0 = a random seed, for hunting
#
# fuzz_gltf first replays its whole seed corpus (the generated seeds of fuzz/corpus/fuzz_gltf and, copied
# at run time by fuzz/make_corpus.py --assimp-gltf, the glTF files of Debian's assimp-testmodels, valid
# and deliberately broken): every seed must pass. Then it mutates in fork mode, where crashes whose
# first frame outside the C/C++ runtime is inside libassimp (a third-party bug, see fuzz/README.md) are
# listed but do not fail the run; a crash in our code, a contract violation or a leak does.
#
# Out-of-memory and timeout reports of fuzz_image_load and fuzz_gltf do not fail the run (they are listed): it runs
# in fork mode with -ignore_ooms/-ignore_timeouts because OpenEXR 3.1 and OpenImageIO 2.4 allocate
# whatever a corrupt header claims (a 2 GB string attribute, a 19 GB scanline buffer for a 6M-texel-wide
# image before load() bounded the claims), which is third-party behaviour, not a crash; see
# fuzz/README.md. fuzz_table_product bounds its own sizes, so there an OOM or a timeout is a finding
# like any other.
#
# Reproduce a finding:  build-fuzz/fuzz/<target> build-fuzz/fuzz-artifacts/<target>/<file>
# (fuzz_table_product: prefix ENVPIS_FUZZ_VERBOSE=1 to print what the input decodes to).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD

SECS=${FUZZ_SECONDS:-60}
GLTF_SECS=${FUZZ_GLTF_SECONDS:-$((SECS * 2 / 3))}
BUILD=${FUZZ_BUILD:-build-fuzz}
PARALLEL=${FUZZ_PARALLEL:-1}
SEED=${FUZZ_SEED:-1}
read -r -a TARGETS <<<"${FUZZ_TARGETS:-fuzz_image_load fuzz_table_product fuzz_gltf}"

t0=$(date +%s)
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DENVPIS_BUILD_FUZZ=ON -DENVPIS_BUILD_TESTS=OFF -DENVPIS_BUILD_BENCH=OFF -DENVPIS_BUILD_APPS=OFF >/dev/null
cmake --build "$BUILD" -j"$(nproc)" --target "${TARGETS[@]}"
echo "fuzz: build $(($(date +%s) - t0)) s"

work=$(mktemp -d "${TMPDIR:-/tmp}/envpis-fuzz.XXXXXX")
trap 'rm -rf "$work"' EXIT
mkdir -p "$BUILD/fuzz-logs"

export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
# Full stacks at allocation time, so that scripts/lsan.supp can match third-party leaks.
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$ROOT/scripts/lsan.supp:print_suppressions=0}

run_target() {  # run_target <target>; returns libFuzzer's status
  local t=$1 dir="$work/$1"
  mkdir -p "$dir/corpus" "$dir/artifacts" "$dir/tmp"
  rm -f "$BUILD/fuzz-logs/$t.log" "$BUILD/fuzz-logs/$t.replay.log"
  cp "fuzz/corpus/$t/"* "$dir/corpus/"
  local secs=$SECS
  [ "$t" = fuzz_gltf ] && secs=$GLTF_SECS
  local args=(-max_total_time="$secs" -artifact_prefix="$dir/artifacts/" -print_final_stats=1
              -rss_limit_mb=3072 -seed="$SEED")
  local asan=detect_leaks=1
  case "$t" in
    fuzz_image_load)
      args+=(-fork=1 -ignore_ooms=1 -ignore_timeouts=1 -timeout=20 -max_len=8192)
      asan+=:fast_unwind_on_malloc=0 ;;
    fuzz_table_product)
      args+=(-timeout=30 -max_len=16384) ;;
    fuzz_gltf)
      python3 fuzz/make_corpus.py --assimp-gltf "$dir/corpus"
      # Seeds up to 160 KB (make_corpus.py's GLTF_MAX_SEED); a dictionary of glTF keys for the JSON.
      args+=(-timeout=20 -max_len=160000 -dict=fuzz/fuzz_gltf.dict)
      ls "$dir/corpus" | wc -l >"$dir/seeds"
      # Replay: every seed must load or fail cleanly, third-party crashes included.
      if ! TMPDIR="$dir/tmp" ASAN_OPTIONS=${ASAN_OPTIONS:-$asan} "$BUILD/fuzz/$t" -runs=0 -timeout=20 -max_len=160000 \
           -rss_limit_mb=3072 -print_final_stats=1 -artifact_prefix="$dir/artifacts/" "$dir/corpus" >"$BUILD/fuzz-logs/$t.replay.log" 2>&1; then
        touch "$dir/replay-failed"
        return 1
      fi
      [ "$secs" = 0 ] && return 0  # (libFuzzer's -max_total_time=0 would mean no limit)
      args+=(-fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1) ;;
  esac
  # TMPDIR: the harness's scratch files and libFuzzer's fork-mode directories stay in $work.
  TMPDIR="$dir/tmp" ASAN_OPTIONS=${ASAN_OPTIONS:-$asan} \
    "$BUILD/fuzz/$t" "${args[@]}" "$dir/corpus" >"$BUILD/fuzz-logs/$t.log" 2>&1
}

in_assimp() {  # in_assimp <target> <input>: whether the input crashes inside libassimp, not in our code
  local report frame
  report=$(TMPDIR="$work" ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0} timeout 120 "$BUILD/fuzz/$1" "$2" 2>&1 || true)
  # The first stack frame in libassimp or at a line of our sources decides (frames of libc, libstdc++,
  # the sanitizers' interceptors and libFuzzer are neither).
  frame=$(grep -E '^ +#[0-9]+ ' <<<"$report" |
          grep -E 'libassimp\.so|/(render|src|fuzz|include/envpis)/[^ ]*\.(cpp|h):[0-9]+' | head -n 1)
  [[ "$frame" == *libassimp.so* ]]
}

report() {  # report <target> <status>
  local t=$1 status=$2 dir="$work/$1" log="$BUILD/fuzz-logs/$1.log" secs=$SECS
  [ "$t" = fuzz_gltf ] && secs=$GLTF_SECS
  # Fork mode (fuzz_image_load, fuzz_gltf) exits with the status of its last job even when that job's
  # OOM (71), timeout (70) or, for fuzz_gltf, crash was ignored: judge it by what it found instead.
  local third_party=0 f
  if [ "$t" = fuzz_gltf ] && { [ -e "$dir/replay-failed" ] || [ "$secs" = 0 ]; }; then
    log="$BUILD/fuzz-logs/$t.replay.log"
    [ -e "$dir/replay-failed" ] && echo "fuzz: $t: a seed of the corpus fails"
  elif [ "$t" = fuzz_gltf ]; then
    for f in $(find "$dir/artifacts" -name 'crash-*'); do
      if in_assimp "$t" "$f"; then
        mv "$f" "$dir/artifacts/assimp-$(basename "$f")"
        third_party=$((third_party + 1))
      fi
    done
    # The last job's crash was one of those: nothing of ours is left to fail the run.
    if [ "$third_party" -gt 0 ] && [ -z "$(find "$dir/artifacts" -name 'crash-*' -o -name 'leak-*')" ]; then
      status=0
    fi
  fi
  if [ "$t" != fuzz_table_product ] && { [ "$status" = 70 ] || [ "$status" = 71 ]; }; then
    status=0
  fi
  if [ -n "$(find "$dir/artifacts" -name 'crash-*' -o -name 'leak-*' | head -n 1)" ]; then
    [ "$status" = 0 ] && status=1
  fi
  # Inputs run: the final stats line, or in fork mode the parent's last "#<runs>: cov: ..." line.
  local runs
  runs=$({ grep -h 'stat::number_of_executed_units' "$log" || true; } | awk '{s = $2} END {print s + 0}')
  if [ "$runs" = 0 ]; then
    runs=$({ grep -E '^#[0-9]+: cov' "$log" || true; } | tail -n 1 | sed -E 's/^#([0-9]+):.*/\1/')
  fi
  local ignored extra="" seeds
  seeds=$(ls "fuzz/corpus/$t" | wc -l)
  [ -f "$dir/seeds" ] && seeds="$seeds + $(($(cat "$dir/seeds") - seeds)) assimp-testmodels"
  [ "$t" = fuzz_gltf ] && extra=", $third_party crash(es) inside assimp"
  ignored=$(find "$dir/artifacts" -name 'oom-*' -o -name 'timeout-*' | wc -l)
  echo "fuzz: $t: $runs inputs in ${secs} s, corpus $seeds seeds -> $(ls "$dir/corpus" | wc -l) inputs, $ignored oom/timeout${extra}, status $status (log: $log)"
  if [ "$status" != 0 ] || [ -n "$(ls -A "$dir/artifacts")" ]; then
    mkdir -p "$BUILD/fuzz-artifacts/$t"
    cp "$dir/artifacts/"* "$BUILD/fuzz-artifacts/$t/" 2>/dev/null || true
    ls "$dir/artifacts" | sed "s|^|fuzz: $t: artifact $BUILD/fuzz-artifacts/$t/|"
  fi
  if [ "$status" != 0 ]; then
    echo "fuzz: $t FAILED; the end of its log:"
    grep -vE '^#[0-9]+|^libpng|^ *NEW_FUNC' "$log" | tail -n 60
  fi
  return "$status"
}

t1=$(date +%s)
declare -A status
if [ "$PARALLEL" = 1 ]; then
  declare -A pids
  for t in "${TARGETS[@]}"; do
    run_target "$t" &
    pids[$t]=$!
  done
  for t in "${TARGETS[@]}"; do
    if wait "${pids[$t]}"; then status[$t]=0; else status[$t]=$?; fi
  done
else
  for t in "${TARGETS[@]}"; do
    if run_target "$t"; then status[$t]=0; else status[$t]=$?; fi
  done
fi

failed=0
for t in "${TARGETS[@]}"; do
  report "$t" "${status[$t]}" || failed=1
done
echo "fuzz: fuzzing $(($(date +%s) - t1)) s"
exit $failed
