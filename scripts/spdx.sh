#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The one-line license identifier at the top of every source file of ours (LICENSE: Apache-2.0).
#   scripts/spdx.sh --check   lists the files without it and exits 1 if there are any (a CTest test)
#   scripts/spdx.sh --fix     inserts it where it is missing, in the file type's comment syntax
# Source files: C++ (.cpp .h .inl), Python, shell, CMake (CMakeLists.txt, .cmake), the templates CMake
# configures (.h.in .cpp.in .cmake.in), JavaScript, CSS and HTML, and extension-less scripts with a
# shebang (.ci/run). Data (scenes, corpora, JSON) and prose (Markdown) are not code and carry none.
# The line is the first one, or the second after a shebang or an HTML doctype (which must stay first).
# Files are git's (tracked and untracked but not ignored, so a new file fails before it is added);
# outside a git checkout, every file under the tree but build directories.
set -euo pipefail
cd "$(dirname "$0")/.."
ID="SPDX-License-Identifier: Apache-2.0"

mode=${1:-}
if [ "$mode" != --check ] && [ "$mode" != --fix ]; then
  echo "usage: $0 --check | --fix" >&2
  exit 2
fi

list_files() {
  if command -v git >/dev/null && git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    git ls-files -z --cached --others --exclude-standard
  else
    find . \( -name .git -o -name 'build*' -o -name node_modules \) -prune -o -type f -print0 | sed -z 's|^\./||'
  fi
}

# Sets `comment` to the comment carrying the identifier for FILE (whose first two lines are l1 and l2),
# empty when FILE is not a source file of ours. Bash builtins only: this runs on every file of the tree.
comment_for() {
  local base=${1##*/}
  comment=
  case "$base" in
    *.cpp | *.h | *.inl | *.h.in | *.cpp.in | *.js | *.mjs) comment="// $ID" ;;
    *.py | *.sh | *.cmake | *.cmake.in | CMakeLists.txt) comment="# $ID" ;;
    *.css) comment="/* $ID */" ;;
    *.html) comment="<!-- $ID -->" ;;
    *.*) ;;
    *) if [[ $l1 =~ ^\#!.*(sh|bash|python3?)$ ]] || [[ $l1 =~ ^\#!.*(sh|bash|python3?)[[:space:]] ]]; then
         comment="# $ID"
       fi ;;
  esac
}

missing=()
while IFS= read -r -d '' f; do
  [ -f "$f" ] || continue  # deleted but still in the index
  l1= l2=
  { IFS= read -r l1 || true; IFS= read -r l2 || true; } <"$f"
  comment_for "$f"
  [ -n "$comment" ] || continue
  # The line is the second when the first must stay first (a shebang, an HTML doctype).
  n=1 at=$l1
  shopt -s nocasematch
  if [[ $l1 == '#!'* || $l1 == '<!doctype'* ]]; then n=2 at=$l2; fi
  shopt -u nocasematch
  [[ $at == *"$ID"* ]] && continue
  if [ "$mode" = --check ]; then
    missing+=("$f")
  else
    # sed cannot insert into an empty file or after a last line without a newline; write it anew.
    { head -n $((n - 1)) "$f"; printf '%s\n' "$comment"; tail -n +"$n" "$f"; } >"$f.spdx.tmp"
    chmod --reference="$f" "$f.spdx.tmp"
    mv "$f.spdx.tmp" "$f"
    echo "spdx: $f"
  fi
done < <(list_files)

if [ ${#missing[@]} -gt 0 ]; then
  printf '%s\n' "${missing[@]}"
  echo "spdx: ${#missing[@]} source file(s) without '$ID' at the top; scripts/spdx.sh --fix adds it" >&2
  exit 1
fi
[ "$mode" = --fix ] || echo "spdx: every source file has '$ID'"
