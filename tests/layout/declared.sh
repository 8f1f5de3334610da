#!/usr/bin/env bash
# The functions a public header declares itself, as the compiler reads them
# (gcc -aux-info on the header alone; `static inline` ones left out): one
# line "NAME HEADER:LINE" each; with --args first, "NAME HEADER:LINE NARGS",
# NARGS the number of parameters ((void) is 0). Used by the exports check
# (exports.sh) and the Fortran bindings' drift check
# (tests/fortran/check_coverage.sh).
#
#   declared.sh [--args] CC INCLUDE_DIRS HEADER...     (INCLUDE_DIRS :-separated)
#
# Exits 1, saying which, if a header does not compile alone.
set -u
args=0
[ "${1:-}" = --args ] && { args=1; shift; }
cc=${1:?usage: declared.sh CC INCLUDE_DIRS HEADER...}
incs=${2:?usage: declared.sh CC INCLUDE_DIRS HEADER...}
shift 2

# The number of parameters of the prototype DECL: commas outside nested
# parentheses (a function pointer's own list) between the outer ones.
nparams() {
  local p=${1#*(} depth=0 n=1 i c
  p=${p%)*}
  [[ $p =~ ^[[:space:]]*void[[:space:]]*$ ]] && { echo 0; return; }
  for ((i = 0; i < ${#p}; i++)); do
    c=${p:i:1}
    case $c in
      '(') depth=$((depth + 1)) ;;
      ')') depth=$((depth - 1)) ;;
      ,) [ $depth = 0 ] && n=$((n + 1)) ;;
    esac
  done
  echo $n
}
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
    [[ $decl =~ ([A-Za-z_][A-Za-z0-9_]*)\ \( ]] || continue
    if [ $args = 1 ]; then
      echo "${BASH_REMATCH[1]} $h:$at $(nparams "${decl#*"${BASH_REMATCH[1]} "}")"
    else
      echo "${BASH_REMATCH[1]} $h:$at"
    fi
  done < "$aux"
done
exit $rc
