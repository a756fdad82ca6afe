#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds the libFuzzer targets of fuzz/ (clang, ASan + UBSan, library instrumented too) in build-fuzz
# and runs each in two phases, on a copy of its seed corpus in a temporary directory (new inputs never
# land in the repository):
#
#   1. replay   every seed of fuzz/corpus/<target>/ (and, for fuzz_gltf, the glTF files of Debian's
#               assimp-testmodels) must pass: no crash, sanitizer report, leak, contract violation, OOM
#               or timeout. This phase is deterministic: it is what can fail on any machine.
#   2. explore  time-boxed mutation (FUZZ_SECONDS). What it finds depends on the machine's speed, so a
#               finding only fails the run when it is in envpis's own code. fuzz_image_load and fuzz_gltf
#               run in fork mode with -ignore_crashes/-ignore_ooms/-ignore_timeouts; each crash or leak
#               they found is replayed with a symbolized stack and classified by its first frame that
#               is either at a line of our sources (render/, src/, fuzz/, include/, apps/) or in a
#               shared library other than the C/C++ runtime: "ours" fails the run; "third-party"
#               (OpenImageIO, OpenEXR, libpng, assimp, ...) is printed and kept as an artifact; one that
#               does not reproduce is printed and kept too. OOMs and timeouts of those two targets are
#               third-party allocation and decoding behaviour (fuzz/README.md) and are listed.
#               fuzz_table_product runs only our code with bounded sizes: any finding fails it.
#
# Reports are symbolized (llvm-symbolizer, Debian's llvm package, installed by scripts/install-deps.sh):
# without it neither the LSan suppressions of scripts/lsan.supp nor the classification could see
# function names or our source lines, so its absence is an error.
#
# Usage: bash scripts/fuzz.sh
# Environment:
#   FUZZ_SECONDS   seconds per target (default 60)
#   FUZZ_GLTF_SECONDS  seconds of mutation for fuzz_gltf after its seed replay (default: two thirds of
#                  FUZZ_SECONDS, so that replay + mutation end with the other targets; 0: replay only)
#   FUZZ_TARGETS   space-separated targets (default: fuzz_image_load fuzz_table_product fuzz_gltf)
#   FUZZ_PARALLEL  1 (default): run the targets at the same time (one per core); 0: one after another
#   FUZZ_BUILD     build directory (default build-fuzz)
#   FUZZ_SEED      libFuzzer's -seed (default 1: on the same code a failure replays; how far the
#                  exploration gets in FUZZ_SECONDS still depends on the machine); 0 = a random seed
#
# Artifacts: build-fuzz/fuzz-artifacts/<target>/ holds every finding, renamed ours-*, thirdparty-* or
# unreproduced-*, each with a .txt of its symbolized report; logs are in build-fuzz/fuzz-logs/.

# Reproduce a finding:  build-fuzz/fuzz/<target> build-fuzz/fuzz-artifacts/<target>/<file>
# (fuzz_table_product: prefix ENVPIS_FUZZ_VERBOSE=1 to print what the input decodes to).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
source scripts/fuzz_owner.sh

SECS=${FUZZ_SECONDS:-60}
GLTF_SECS=${FUZZ_GLTF_SECONDS:-$((SECS * 2 / 3))}
BUILD=${FUZZ_BUILD:-build-fuzz}
PARALLEL=${FUZZ_PARALLEL:-1}
SEED=${FUZZ_SEED:-1}
read -r -a TARGETS <<<"${FUZZ_TARGETS:-fuzz_image_load fuzz_table_product fuzz_gltf}"

# The symbolizer of clang's sanitizer runtime (see the header).
SYMBOLIZER=${ASAN_SYMBOLIZER_PATH:-$(command -v llvm-symbolizer || command -v llvm-symbolizer-14 || true)}
if [ -z "$SYMBOLIZER" ] || [ ! -x "$SYMBOLIZER" ]; then
  echo "fuzz: llvm-symbolizer not found (Debian package llvm; scripts/install-deps.sh installs it)" >&2
  exit 1
fi
export ASAN_SYMBOLIZER_PATH=$SYMBOLIZER

t0=$(date +%s)
# OpenImageIO's glue linked in (ENVPIS_OIIO_AS_MODULE=OFF), not loaded with dlopen: libFuzzer registers
# the coverage counters of the modules loaded at start-up only, so the glue's code would guide nothing.
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DENVPIS_BUILD_FUZZ=ON -DENVPIS_BUILD_TESTS=OFF -DENVPIS_BUILD_BENCH=OFF -DENVPIS_BUILD_APPS=OFF \
  -DENVPIS_OIIO_AS_MODULE=OFF >/dev/null
cmake --build "$BUILD" -j"$(nproc)" --target "${TARGETS[@]}"
echo "fuzz: build $(($(date +%s) - t0)) s"

work=$(mktemp -d "${TMPDIR:-/tmp}/envpis-fuzz.XXXXXX")
trap 'rm -rf "$work"' EXIT
mkdir -p "$BUILD/fuzz-logs"

export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$ROOT/scripts/lsan.supp:print_suppressions=0}
# ASAN_FULL: full stacks at allocation time, through the uninstrumented libraries (no frame pointers)
# too, so that a leak's stack shows where it was allocated: for fuzz_image_load, whose allocations are
# mostly OpenImageIO's and OpenEXR's, and for classifying every finding. It slows each malloc, so the
# other targets fuzz with fast unwinding.
ASAN_FAST=${ASAN_OPTIONS:-detect_leaks=1}
ASAN_FULL=${ASAN_OPTIONS:-detect_leaks=1:fast_unwind_on_malloc=0}

target_secs() { if [ "$1" = fuzz_gltf ]; then echo "$GLTF_SECS"; else echo "$SECS"; fi; }

run_target() {  # run_target <target>: the replay, then the exploration; returns 1 if the replay failed
  local t=$1 dir="$work/$1" secs
  secs=$(target_secs "$t")
  mkdir -p "$dir/corpus" "$dir/artifacts" "$dir/replay-artifacts" "$dir/tmp"
  rm -f "$BUILD/fuzz-logs/$t.log" "$BUILD/fuzz-logs/$t.replay.log"
  cp "fuzz/corpus/$t/"* "$dir/corpus/"
  local limits=(-rss_limit_mb=3072 -timeout=20)
  local args=(-max_total_time="$secs" -artifact_prefix="$dir/artifacts/" -print_final_stats=1 -seed="$SEED")
  case "$t" in
    fuzz_image_load) args+=(-max_len=8192) ;;
    fuzz_table_product) args+=(-max_len=16384); limits=(-rss_limit_mb=3072 -timeout=30) ;;
    fuzz_gltf)
      python3 fuzz/make_corpus.py --assimp-gltf "$dir/corpus"
      # Seeds up to 160 KB (make_corpus.py's GLTF_MAX_SEED); a dictionary of glTF keys for the JSON.
      args+=(-max_len=160000 -dict=fuzz/fuzz_gltf.dict) ;;
  esac
  ls "$dir/corpus" | wc -l >"$dir/seeds"
  local asan=$ASAN_FAST
  [ "$t" = fuzz_image_load ] && asan=$ASAN_FULL
  # 1. Replay: every seed must load or fail cleanly, third-party code included. It judges outcomes, not
  # speed: its timeout is 300 s per seed, since under ASan exr_claims_8M_wide takes 16 s on an idle
  # 2-core machine and 35-45 s on a loaded one (OpenEXR sizes its line buffers from the claim before
  # load() can refuse it). TMPDIR: the harness's scratch files (and libFuzzer's fork-mode directories
  # below) stay in $work.
  if ! TMPDIR="$dir/tmp" ASAN_OPTIONS=$asan "$BUILD/fuzz/$t" -runs=0 -rss_limit_mb=3072 -timeout=300 -print_final_stats=1 \
       -artifact_prefix="$dir/replay-artifacts/" "$dir/corpus" >"$BUILD/fuzz-logs/$t.replay.log" 2>&1; then
    touch "$dir/replay-failed"
    return 1
  fi
  [ "$secs" = 0 ] && return 0  # (libFuzzer's -max_total_time=0 would mean no limit)
  # 2. Exploration.
  if [ "$t" != fuzz_table_product ]; then args+=(-fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1); fi
  TMPDIR="$dir/tmp" ASAN_OPTIONS=$asan "$BUILD/fuzz/$t" "${args[@]}" "${limits[@]}" "$dir/corpus" \
    >"$BUILD/fuzz-logs/$t.log" 2>&1 || echo $? >"$dir/explore-status"
  return 0
}

# classify <target> <input> <report file>: replays the input, writes its report, and prints "ours",
# "third-party <library>" or "unreproduced" (scripts/fuzz_owner.sh decides; a report without any frame
# of ours or of a library counts as ours, to be looked at).
classify() {
  local status=0 owner
  TMPDIR="$work" ASAN_OPTIONS=$ASAN_FULL timeout 120 "$BUILD/fuzz/$1" -timeout=20 -rss_limit_mb=3072 "$2" \
    >"$3" 2>&1 || status=$?
  if [ "$status" = 0 ]; then echo unreproduced; return; fi
  owner=$(fuzz_owner "$3" "$ROOT")
  if [ "$owner" = none ]; then echo ours; else echo "$owner"; fi
}

report() {  # report <target>: prints what the target did; returns 1 if the run must fail
  local t=$1 dir="$work/$1" secs log
  secs=$(target_secs "$t")
  log="$BUILD/fuzz-logs/$t.log"
  local out="$BUILD/fuzz-artifacts/$t"
  if [ -e "$dir/replay-failed" ]; then
    mkdir -p "$out"
    cp "$dir/replay-artifacts/"* "$out/" 2>/dev/null || true
    echo "fuzz: $t FAILED: a seed of the fixed corpus fails (log: $BUILD/fuzz-logs/$t.replay.log); its end:"
    grep -vE '^#[0-9]+|^ *NEW_FUNC' "$BUILD/fuzz-logs/$t.replay.log" | tail -n 60
    return 1
  fi
  local seeds
  seeds=$(ls "fuzz/corpus/$t" | wc -l)
  [ "$t" = fuzz_gltf ] && seeds="$seeds + $(($(cat "$dir/seeds") - seeds)) assimp-testmodels"
  echo "fuzz: $t: replayed $(cat "$dir/seeds") seeds ($seeds): all pass"
  [ "$secs" = 0 ] && return 0
  # Findings of the exploration.
  local ours=0 third=0 unrepro=0 f class name
  for f in $(find "$dir/artifacts" -maxdepth 1 -type f \( -name 'crash-*' -o -name 'leak-*' \) | sort); do
    mkdir -p "$out"
    class=$(classify "$t" "$f" "$work/report.txt")
    case "$class" in
      ours) name="ours-$(basename "$f")"; ours=$((ours + 1)) ;;
      unreproduced) name="unreproduced-$(basename "$f")"; unrepro=$((unrepro + 1)) ;;
      *) name="thirdparty-${class#third-party }-$(basename "$f")"; third=$((third + 1)) ;;
    esac
    cp "$f" "$out/$name"
    cp "$work/report.txt" "$out/$name.txt"
    echo "fuzz: $t: finding $out/$name: $class"
    if [ "$class" = ours ]; then
      { grep -E 'ERROR|SUMMARY|runtime error|contract violated|^ +#[0-9]+ ' "$out/$name.txt" || true; } | head -n 30
    fi
  done
  local ignored
  ignored=$(find "$dir/artifacts" -name 'oom-*' -o -name 'timeout-*' | wc -l)
  if [ "$ignored" -gt 0 ]; then
    mkdir -p "$out"
    find "$dir/artifacts" \( -name 'oom-*' -o -name 'timeout-*' \) -exec cp {} "$out/" \;
  fi
  # Inputs run: the final stats line, or in fork mode the parent's last "#<runs>: cov: ..." line.
  local runs
  runs=$({ grep -h 'stat::number_of_executed_units' "$log" || true; } | awk '{s = $2} END {print s + 0}')
  if [ "$runs" = 0 ]; then
    runs=$({ grep -E '^#[0-9]+: cov' "$log" || true; } | tail -n 1 | sed -E 's/^#([0-9]+):.*/\1/')
  fi
  echo "fuzz: $t: explored ${runs:-0} inputs in $secs s -> $(ls "$dir/corpus" | wc -l) inputs; findings: $ours ours," \
       "$third third-party, $unrepro unreproduced, $ignored oom/timeout (log: $log)"
  if [ "$t" = fuzz_table_product ]; then
    # Our code only: any finding, OOM or timeout included, and any failure of libFuzzer itself.
    if [ -e "$dir/explore-status" ] || [ -n "$(ls -A "$dir/artifacts")" ]; then
      mkdir -p "$out"
      cp "$dir/artifacts/"* "$out/" 2>/dev/null || true
      echo "fuzz: $t FAILED (status $(cat "$dir/explore-status" 2>/dev/null || echo 0)); the end of its log:"
      grep -vE '^#[0-9]+|^ *NEW_FUNC' "$log" | tail -n 60
      return 1
    fi
    return 0
  fi
  # Fork mode ends with the status of its last job, ignored finding or not: a status without any
  # finding means libFuzzer itself failed.
  if [ -e "$dir/explore-status" ] && [ -z "$(ls -A "$dir/artifacts")" ]; then
    echo "fuzz: $t FAILED: libFuzzer exited with status $(cat "$dir/explore-status") without a finding; the end of its log:"
    tail -n 40 "$log"
    return 1
  fi
  if [ "$ours" -gt 0 ]; then
    echo "fuzz: $t FAILED: $ours finding(s) in envpis's own code"
    return 1
  fi
  return 0
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
  report "$t" || failed=1
done
echo "fuzz: fuzzing $(($(date +%s) - t1)) s"
exit $failed
