# SPDX-License-Identifier: Apache-2.0
# Sourced by scripts/fuzz.sh (and its test, tests/fuzz_owner_test.sh): who owns a sanitizer report.
#
# fuzz_owner <report file> <repository root>: prints "ours", "third-party <library>.so" or "none" for
# a symbolized ASan / LSan / UBSan / libFuzzer report. The first stack frame that is either at a line of
# our sources (render/, src/, fuzz/, include/, apps/ under the root) or in a shared library other than
# the C/C++ runtime decides. Frames of the sanitizers' interceptors and of libFuzzer are in the fuzz
# binary itself, those of the C/C++ runtime (libc, libstdc++, ...) and of inlined standard headers
# belong to whoever called them: all of these are skipped.
fuzz_owner() {
  local frame
  frame=$(grep -E '^ +#[0-9]+ ' "$1" |
          grep -E "$2/(render|src|fuzz|include|apps)/[^ ]*:[0-9]+|\(/[^ ]*\.so[.0-9]*\+0x" |
          grep -vE '/(libc|libm|libstdc\+\+|libgcc_s|libpthread|libdl|libasan|libubsan)\.so|/ld-linux' |
          head -n 1 || true)
  if [[ "$frame" == *" $2/"* ]]; then
    echo ours
  elif [ -n "$frame" ]; then
    echo "third-party $(sed -E 's|.*\(/[^ ]*/([^/ ]*\.so)[.0-9]*\+0x.*|\1|' <<<"$frame")"
  else
    echo none
  fi
}
