#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Checks scripts/fuzz_owner.sh, which decides whether a finding of the fuzzers' exploration fails CI
# (ours) or is only kept (third-party): canned reports shaped like clang 14's symbolized ones.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/fuzz_owner.sh
root=/ci/clone/main
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failed=0 passed=0
expect() {  # expect <name> <expected owner> <report lines...>
  local name=$1 want=$2 got
  shift 2
  printf '%s\n' "$@" >"$tmp/$name"
  got=$(fuzz_owner "$tmp/$name" "$root")
  if [ "$got" != "$want" ]; then echo "FAIL $name: got '$got', want '$want'"; failed=$((failed + 1)); else echo "ok   $name: $got"; passed=$((passed + 1)); fi
}
interceptor='    #0 0x55f0 in operator new(unsigned long) (/ci/clone/main/build-fuzz/fuzz/fuzz_image_load+0x10d391) (BuildId: 7875)'
libstdcxx='    #1 0x7f23 in std::__cxx11::basic_string<char>::_M_construct (/lib/x86_64-linux-gnu/libstdc++.so.6+0x14b0bd) (BuildId: 93ac)'
oiio='    #2 0x7f23 in OpenImageIO_v2_4::PNGInput::PngReadCallback (/lib/x86_64-linux-gnu/libOpenImageIO.so.2.4+0x67643a) (BuildId: b983)'
ours_load="    #3 0x55f0 in envpis::EnvironmentMap::load(std::string const&) $root/src/io/environment_map_load.cpp:205:11"
header='    #0 0x55f0 in std::vector<float>::operator[](unsigned long) /usr/bin/../lib/gcc/x86_64-linux-gnu/12/../../../../include/c++/12/bits/stl_vector.h:1123:2'
libc_memset='    #4 0x7f23 in __memset_avx512_unaligned_erms string/../sysdeps/x86_64/multiarch/memset-vec-unaligned-erms.S:235'
libc='    #3 0x7f23  (/lib/x86_64-linux-gnu/libc.so.6+0x3c04f) (BuildId: 93ac)'
fuzzer='    #9 0x55f0 in fuzzer::Fuzzer::ExecuteCallback(unsigned char const*, unsigned long) (/ci/clone/main/build-fuzz/fuzz/fuzz_gltf+0x669a3)'

expect leak-in-openimageio "third-party libOpenImageIO.so" "Direct leak of 31 byte(s) in 1 object(s) allocated from:" \
  "$interceptor" "$libstdcxx" "$oiio" "$ours_load" "$fuzzer"
expect leak-in-our-code ours "Direct leak of 64 byte(s) in 1 object(s) allocated from:" "$interceptor" "$ours_load" "$fuzzer"
expect overflow-through-std-header ours "ERROR: AddressSanitizer: heap-buffer-overflow" "$header" \
  "    #1 0x55f0 in envpis::render::load_gltf(std::string const&) $root/render/gltf.cpp:301:7" "$fuzzer"
expect libc-then-openexr "third-party libOpenEXR-3_1.so" "ERROR: libFuzzer: deadly signal" "$libc" "$libc_memset" \
  "    #7 0x7f23 in Imf_3_1::ScanLineInputFile::~ScanLineInputFile() (/lib/x86_64-linux-gnu/libOpenEXR-3_1.so.30+0xd8ee8)" \
  "$ours_load"
expect contract-violation ours "fuzz_image_load: contract violated: texel not finite" "$libc" \
  "    #2 0x55f0 in (anonymous namespace)::violated(char const*, std::string const&) $root/fuzz/fuzz_image_load.cpp:49:3" "$fuzzer"
expect assimp-crash "third-party libassimp.so" "ERROR: AddressSanitizer: SEGV on unknown address" \
  "    #0 0x7f11 in Assimp::glTF2Importer::ImportNodes (/lib/x86_64-linux-gnu/libassimp.so.5+0x5f1a2c)" \
  "    #1 0x55f0 in envpis::render::load_gltf(std::string const&) $root/render/gltf.cpp:350:3"
expect another-checkout none "ERROR: AddressSanitizer: SEGV" \
  "    #0 0x55f0 in envpis::ImportanceTable::sample /elsewhere/main/src/importance_table.cpp:10:1" "$fuzzer"
expect no-frames none "ERROR: libFuzzer: out-of-memory (malloc(4294967296))"
echo "fuzz_owner: $passed passed, $failed failed"
[ "$failed" = 0 ]
