#!/usr/bin/env bash
# The functions a public header declares itself, as the compiler reads them
# (gcc -aux-info on the header alone; `static inline` ones left out): one
# line "NAME HEADER:LINE" each. Used by the exports check (exports.sh) and
# the Fortran bindings' drift check (tests/fortran/check_coverage.sh).
#
#   declared.sh CC INCLUDE_DIRS HEADER...     (INCLUDE_DIRS :-separated)
#
# Exits 1, saying which, if a header does not compile alone.
set -u
cc=${1:?usage: declared.sh CC INCLUDE_DIRS HEADER...}
incs=${2:?usage: declared.sh CC INCLUDE_DIRS HEADER...}
shift 2
aux=$(mktemp)
trap 'rm -f "$aux"' EXIT
iflags=()
IFS=: read -ra dirs <<< "$incs"
for d in "${dirs[@]}"; do iflags+=("-I$d"); done
rc=0
for h in "$@"; do
  real=$(realpath "$h")
  if ! "$cc" -fsyntax-only -aux-info "$aux" "${iflags[@]}" -x c "$h"; then
    echo "declared: $h: does not compile alone" >&2; rc=1; continue
  fi
  while IFS= read -r line; do
    [[ $line =~ ^/\*\ ([^:]+):([0-9]+):[^*]*\*/\ (.*)$ ]] || continue
    file=${BASH_REMATCH[1]} at=${BASH_REMATCH[2]} decl=${BASH_REMATCH[3]}
    [ "$(realpath "$file")" = "$real" ] || continue
    [[ ${decl%%(*} == *static* ]] && continue
    [[ $decl =~ ([A-Za-z_][A-Za-z0-9_]*)\ \( ]] && echo "${BASH_REMATCH[1]} $h:$at"
  done < "$aux"
done
exit $rc
