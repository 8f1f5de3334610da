#!/usr/bin/env bash
# The tree reads nothing outside itself: no file the build, the tests, the
# scripts or the examples use names a path beside the checkout (the design
# notes' folder next to the checkout is reading material only). Markdown
# may tell where data first came from; everything else may not point there.
# Nor may a file cite the design notes by their outside name: the design
# the code cites is docs/design.md.
#   self_contained.sh SOURCE_DIR
#   self_contained.sh --self-test     (the check fails on a tree that reads outside)
set -euo pipefail
if [ "$1" = --self-test ]; then
  t=$(mktemp -d); trap 'rm -rf "$t"' EXIT
  mkdir -p "$t/tests/data" "$t/scripts"
  touch "$t/tests/data/ref_case1_limit_richardson.csv"   # empty: caught
  echo x > "$t/tests/data/ref_case2_limit_richardson.csv"
  if bash "$0" "$t" 2>/dev/null; then echo "self-test: an empty data file passed" >&2; exit 1; fi
  echo x > "$t/tests/data/ref_case1_limit_richardson.csv"
  bash "$0" "$t" >/dev/null || { echo "self-test: a clean tree failed" >&2; exit 1; }
  printf 'ref=$(cd ../%s/reference && pwd)\n' shared > "$t/scripts/bench"
  if bash "$0" "$t" 2>/dev/null; then echo "self-test: a read outside passed" >&2; exit 1; fi
  rm "$t/scripts/bench"
  printf '/* the contract (%s.md) */\n' DESIGN > "$t/scripts/cite.c"
  if bash "$0" "$t" 2>/dev/null; then echo "self-test: a citation of the outside notes passed" >&2; exit 1; fi
  echo "self_contained --self-test: the check catches a read outside, a citation outside and a missing file"
  exit 0
fi
src=$1
pattern='\.\./'"shared"'|/shared/'"reference"
hits=$(grep -rInE "$pattern" "$src" \
         --exclude-dir=.git --exclude-dir='build*' --exclude-dir=.venv \
         --exclude-dir=out --exclude-dir=bench-out --exclude='*.md' || true)
if [ -n "$hits" ]; then
  echo "files that read outside the repository:" >&2
  echo "$hits" >&2
  exit 1
fi
cites=$(grep -rIn "DESIGN"'\.md' "$src" --exclude-dir=.git --exclude-dir='build*' \
          --exclude-dir=.venv --exclude-dir=out --exclude-dir=bench-out || true)
if [ -n "$cites" ]; then
  echo "files that cite the design notes outside the repository (cite docs/design.md):" >&2
  echo "$cites" >&2
  exit 1
fi
for f in ref_case1_limit_richardson.csv ref_case2_limit_richardson.csv; do
  [ -s "$src/tests/data/$f" ] || { echo "tests/data/$f is missing" >&2; exit 1; }
done
echo "self_contained: nothing in $src reads outside it"
