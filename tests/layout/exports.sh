#!/usr/bin/env bash
# What the shared libraries export is exactly what the public headers
# declare: `cup_` means public.
#
#   exports.sh CC INCLUDE_DIRS LIB=HEADER... [LIB=HEADER...]...
#
# INCLUDE_DIRS is a :-separated list (the source tree's include/ and the
# build tree's, which has the generated catchup/version.h). Each LIB is
# followed by the headers whose functions it must export (an argument
# LIB=H1:H2:...). The functions a header declares come from the compiler
# itself (declared.sh: gcc -aux-info on the header alone);
# the exports from `nm -D --defined-only LIB`. Fails, naming the symbol and
# what to do, on
#   * an exported symbol that no header of its library declares: an internal
#     function with CUP_API, or built without -fvisibility=hidden;
#   * a declared function that the library does not export: its declaration
#     lacks CUP_API (include/catchup/export.h), or nothing defines it;
#   * any exported symbol outside the cup_ prefix.
# Prints one line per problem and exits 1 if there is any.
set -u
export LC_ALL=C   # sort and join agree on the order
cc=${1:?usage: exports.sh CC INCLUDE_DIRS LIB=HEADER[:HEADER...]...}
incs=${2:?usage: exports.sh CC INCLUDE_DIRS LIB=HEADER[:HEADER...]...}
shift 2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
bad=0
say() { echo "exports: $*"; bad=1; }
here=$(cd "$(dirname "$0")" && pwd)

total=0
for arg in "$@"; do
  lib=${arg%%=*}
  name=$(basename "$lib")
  [ -f "$lib" ] || { say "$lib: no such library (build first)"; continue; }
  IFS=: read -ra headers <<< "${arg#*=}"
  bash "$here/declared.sh" "$cc" "$incs" "${headers[@]}" > "$work/decl" ||
    say "${headers[*]}: cannot list their declarations"
  sort -u -k1,1 "$work/decl" > "$work/decl.sorted"
  nm -D --defined-only "$lib" | awk 'NF == 3 {print $3}' | sort -u > "$work/exp"
  while read -r sym; do
    case $sym in
      cup_*) say "$name exports $sym, which no public header of it declares: an internal" \
                 "function must not carry CUP_API (cup_ means public; rename it or move its" \
                 "declaration to include/catchup/)" ;;
      *) say "$name exports $sym, outside the cup_ prefix: the library must be built with" \
             "-fvisibility=hidden (C_VISIBILITY_PRESET hidden) and mark only public functions CUP_API" ;;
    esac
  done < <(join -v1 "$work/exp" <(cut -d' ' -f1 "$work/decl.sorted"))
  while read -r sym where; do
    say "$where: $sym is declared but $name does not export it: write CUP_API before" \
        "its declaration (include/catchup/export.h), and define it in the library"
  done < <(join -v1 "$work/decl.sorted" "$work/exp")
  total=$((total + $(wc -l < "$work/exp")))
done

[ $bad = 0 ] && echo "exports: $total symbols exported by $#" \
  "libraries, each declared by a public header with CUP_API, all cup_"
exit $bad
