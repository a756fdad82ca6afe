#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Sanitizer runs (a CI step, after scripts/test.sh), each in its own build directory, with GCC (the
# project's compiler; the fuzzers in scripts/fuzz.sh are the clang builds):
#
#   asan  build-asan: library, renderer, envpis command and tests with AddressSanitizer + UBSan
#         (-O1 -g, -fno-sanitize-recover=undefined: the first UB report fails the test; plus
#         float-cast-overflow, which GCC leaves out of "undefined" and clang does not), then
#         `ctest -L unit` (every test but the slow `sweep` label), minus ASAN_EXCLUDE below.
#   tsan  build-tsan: ThreadSanitizer on the multi-threaded tests: the renderer's determinism test
#         (tests/render: same image at 1 and 2 threads) and the library's concurrent-sampling test
#         (tests whose name contains "Thread"); if tests/render has no such test, only the library's.
#         Only the test executables that contain them are built. Limitation: Debian's libtbb is not
#         instrumented, so TSan cannot see TBB's synchronization; scripts/tsan.supp suppresses the
#         resulting false positives, and with them races between TBB tasks (see that file).
#
# Usage: bash scripts/sanitize.sh [asan|tsan]...   (default: both)
# Environment: SANITIZE_CXX (default g++), SANITIZE_JOBS (default nproc),
#              ASAN_BUILD / TSAN_BUILD (default build-asan / build-tsan),
#              ASAN_EXCLUDE (ctest -E regex, default below; empty string runs everything).
#
# The dependencies (scripts/install-deps.sh) must be installed; scripts/test.sh does that first in CI.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD

CXX_BIN=${SANITIZE_CXX:-g++}
JOBS=${SANITIZE_JOBS:-$(nproc)}
ASAN_BUILD=${ASAN_BUILD:-build-asan}
TSAN_BUILD=${TSAN_BUILD:-build-tsan}
# Tests left out under ASan, each a statistical convergence test (z-tests of rendered images) whose
# code paths other unit tests run under ASan; together they took 240 s of the ASan run's 2090 s of CPU:
#   PortalRender.EveryStrategyConvergesWithPortalsOnOffAndHalf (12 million samples): the portal
#     strategies run under ASan in the other PortalRender tests (path integrator, sample/pdf agreement);
#   AssetConvergence.EveryStrategyMatchesTheReferencePerObject (149 s under ASan): every asset scene
#     renders under ASan in AssetScenes.EveryAssetSceneLoadsWithItsAssetsAndRendersFinitePixels;
#   Regularization.FilterGlossyEveryStrategyConvergesToTheSameImage (93 s): filter glossy runs under
#     ASan in Regularization.FilterGlossyWidensWhatIsSampledEvaluatedAndProxied and the others.
# and five chi-square and quadrature tests of the library (about 470 s of CPU under ASan, which brought
# the whole CI run to 2535 s of its 2700 s budget), whose code runs under ASan in smaller tests:
#   ImportanceTable.PeakBoundCapsEveryLightSampleWeight (124 s): the bound is built by every table;
#   TexelPeak.SameBitsAsTheMaxTreeAlgorithm (89 s): the texel peak is computed by every table build;
#   ProductSampler.MomentsChiSquareOverManyConfigurations (98 s) and
#     ProductSampler.MomentsEstimateFollowsTheCellMassesBetter (82 s): the moments estimate runs in
#     ProductSampler.MomentsKernelsMatchTheScalarKernels and in every rendered product test;
#   Analyzer.QuadratureConverges (79 s): the analyzer runs in Analyzer.AgreesWithTheRenderersSampleVariance.
# and three more (2026-12-04: a fresh-Debian run of .ci/run took 2801 s, sanitize 1797 s of it, after the
# equal-area tables became the default under bilinear look-ups, which cost more to build under ASan):
#   ProductSampler.ChiSquareOverManyConfigurations (82 s): product sampling runs under ASan in
#     ProductSampler.RefinedChiSquareOverManyConfigurations and SamplePdfEqualsPdfOfDirectionAndIntegratesToOne;
#   Convergence.EveryStrategyMatchesReferencePerSphere (87 s): every strategy renders under ASan in the
#     other render tests (Render.*, CompareCommand.SmallRunWritesConsistentMetricsImagesAndReport);
#   MapTexels.ProductSamplingChiSquare (52 s): the product over map texels runs under ASan in
#     MapTexels.SamplePdfAndInvertAgree and MapTexels.EnvironmentSamplingChiSquare.
# and the two tests of --product-compensation (2026-12-04; 2 s and 3 s here, a sunset table and a
# 2048-spp reference under ASan), whose code runs under ASan in
#   LightSampler.ProductAtGlossyVerticesUsesOneDensityPerVertex (the product over the compensated table
#   and the compensated table at the other vertices, sampled and evaluated):
#   ProductSampler.CompensatedTableChiSquare (the only test that reaches ImportanceTable::sample's
#   redraw at a zero texel's edge, about once in 10^5 draws: that branch is not run under ASan),
#   Convergence.CompensatedProductMatchesReferencePerSphere.
# and one more (2026-12-05: a fresh-Debian run of .ci/run took 2987 s, sanitize 1965 s of it, after the
# renderer's product began to build a second, compensated table; that table is now left out where nothing
# samples it, and this test alone took 263 s under ASan):
#   CompareCommand.SmallRunWritesConsistentMetricsImagesAndReport (27 s in Release): `compare` runs under
#     ASan end to end in CompareCommand.SeedsReportMediansOverIndependentRenders and
#     CompareCommand.AnalysisInMetricsAndReport, the oracle in the Oracle tests.
ASAN_EXCLUDE=${ASAN_EXCLUDE-PortalRender.EveryStrategyConvergesWithPortalsOnOffAndHalf|AssetConvergence.EveryStrategyMatchesTheReferencePerObject|Regularization.FilterGlossyEveryStrategyConvergesToTheSameImage|ImportanceTable.PeakBoundCapsEveryLightSampleWeight|TexelPeak.SameBitsAsTheMaxTreeAlgorithm|ProductSampler.MomentsChiSquareOverManyConfigurations|ProductSampler.MomentsEstimateFollowsTheCellMassesBetter|Analyzer.QuadratureConverges|ProductSampler.ChiSquareOverManyConfigurations|Convergence.EveryStrategyMatchesReferencePerSphere|MapTexels.ProductSamplingChiSquare|ProductSampler.CompensatedTableChiSquare|Convergence.CompensatedProductMatchesReferencePerSphere|CompareCommand.SmallRunWritesConsistentMetricsImagesAndReport}

steps=("$@")
[ ${#steps[@]} -eq 0 ] && steps=(asan tsan)

now() { date +%s; }
log() { echo "sanitize: $*"; }

# Third-party libraries (OpenImageIO, Embree, TBB, GoogleTest) are not instrumented; the library, the
# renderer and the tests are. Leaks found inside third-party code on error paths are suppressed in
# scripts/lsan.supp (each entry says why).
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:check_initialization_order=1:strict_init_order=1:detect_stack_use_after_return=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$ROOT/scripts/lsan.supp:print_suppressions=0}
export TSAN_OPTIONS=${TSAN_OPTIONS:-suppressions=$ROOT/scripts/tsan.supp:halt_on_error=1:second_deadlock_stack=1:history_size=4}

# OpenImageIO linked, not loaded with dlopen (ENVPIS_OIIO_AS_MODULE=OFF): GCC 12's LeakSanitizer crashed
# at exit ("Tracer caught signal 11") in every ctest run of a test that had loaded the module, and in no
# run of the same test outside ctest; the cause was not found.
# No Python module: an instrumented extension only loads into a Python started with the sanitizer
# runtime preloaded, and the runs below are GoogleTest's (`-L unit`, the Thread tests).
configure() {  # configure <dir> <sanitizer flags> <build the envpis command: ON|OFF>
  local dir=$1 flags=$2 apps=$3 cxx
  cxx=$(command -v "$CXX_BIN")
  # A build directory configured with another compiler cannot be switched: start it afresh.
  if [ -f "$dir/CMakeCache.txt" ] && ! grep -qx "CMAKE_CXX_COMPILER:[A-Z]*=$cxx" "$dir/CMakeCache.txt"; then
    log "$dir was configured with another compiler: removing it"
    rm -rf "$dir"
  fi
  cmake -S . -B "$dir" -G Ninja -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=Debug \
    -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" -DCMAKE_CXX_FLAGS="$flags -fno-omit-frame-pointer" \
    -DCMAKE_EXE_LINKER_FLAGS="$flags" -DCMAKE_SHARED_LINKER_FLAGS="$flags" \
    -DENVPIS_BUILD_TESTS=ON -DENVPIS_BUILD_BENCH=OFF -DENVPIS_BUILD_APPS="$apps" -DENVPIS_BUILD_FUZZ=OFF \
    -DENVPIS_BUILD_PYTHON=OFF -DENVPIS_OIIO_AS_MODULE=OFF >/dev/null
}

run_asan() {
  local t0
  t0=$(now)
  # With the envpis command: its tests feed it bad files and options, which ASan should watch too.
  configure "$ASAN_BUILD" "-fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=undefined,float-cast-overflow" ON
  cmake --build "$ASAN_BUILD" -j"$JOBS"
  local t1
  t1=$(now)
  local exclude=()
  [ -n "$ASAN_EXCLUDE" ] && exclude=(-E "$ASAN_EXCLUDE")
  local rc=0
  ctest --test-dir "$ASAN_BUILD" -L unit "${exclude[@]}" --output-on-failure -j"$JOBS" --timeout 900 || rc=$?
  log "asan: build $((t1 - t0)) s, tests $(($(now) - t1)) s"
  return $rc
}

# The executables (target names) of the test files that hold the TSan tests: the renderer's
# determinism test if it exists, and the library's thread-safety tests.
tsan_targets() {
  local f
  for f in tests/render/test_*.cpp; do
    [ -f "$f" ] && grep -qE '^TEST(_F)?\(.*(Determinism|Thread)' "$f" && basename "$f" .cpp
  done
  for f in tests/test_*.cpp; do
    [ -f "$f" ] && grep -qE '^TEST(_F)?\(.*Thread' "$f" && basename "$f" .cpp
  done
  return 0
}

run_tsan() {
  local t0
  t0=$(now)
  mapfile -t targets < <(tsan_targets)
  if [ ${#targets[@]} -eq 0 ]; then
    log "tsan: no test with Determinism or Thread in its name was found" >&2
    return 1
  fi
  if ! printf '%s\n' "${targets[@]}" | grep -qx test_render; then
    log "tsan: tests/render has no determinism test yet: running the library's Thread tests only"
  fi
  configure "$TSAN_BUILD" "-fsanitize=thread" OFF
  cmake --build "$TSAN_BUILD" -j"$JOBS" --target "${targets[@]}"
  local t1
  t1=$(now)
  # ThreadSanitizer needs a narrow address space layout; kernels with 32 random mmap bits break clang
  # 14's TSan ("unexpected memory mapping"), so the tests run with address randomization off.
  local norand=()
  command -v setarch >/dev/null && norand=(setarch "$(uname -m)" -R)
  local rc=0
  "${norand[@]}" ctest --test-dir "$TSAN_BUILD" -R 'Determinism|Thread' --output-on-failure -j1 --timeout 1200 \
    --no-tests=error || rc=$?
  log "tsan: build $((t1 - t0)) s (${targets[*]}), tests $(($(now) - t1)) s"
  return $rc
}

for s in "${steps[@]}"; do
  case "$s" in
    asan) run_asan ;;
    tsan) run_tsan ;;
    *) echo "usage: $0 [asan|tsan]..." >&2; exit 2 ;;
  esac
done
