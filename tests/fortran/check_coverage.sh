#!/usr/bin/env bash
# The Fortran module cannot silently fall behind the C API. Its raw bind(C)
# interfaces are generated from the headers at build time
# (src/fortran/gen_bindings.py, which stops on a function it cannot map);
# this check runs that generator on the tree and fails, naming the function
# and what to do, when
#   * a function of the public headers has no bind(C) interface that a
#     module of src/fortran includes, and is not on the generator's SKIP;
#   * a bind(C) interface names no public function (one written by hand in
#     src/fortran that was renamed or removed in C);
#   * a bind(C) interface takes more or fewer arguments than the compiler's
#     reading of the C declaration (gcc -aux-info: the generator's own
#     reading of the headers is checked against it);
#   * a bind(C) interface is never called by a wrapper (c_cup_x declared but
#     unused: `use catchup` does not offer it) and is not on RAW_ONLY;
#   * an entry of RAW_ONLY no longer applies.
#
#   check_coverage.sh CC INCLUDE_DIRS SRCDIR
#
# INCLUDE_DIRS (:-separated) must find the generated catchup/version.h.
set -u
export LC_ALL=C
here=$(cd "$(dirname "$0")" && pwd)
cc=${1:?usage: check_coverage.sh CC INCLUDE_DIRS SRCDIR}
incs=${2:?usage: check_coverage.sh CC INCLUDE_DIRS SRCDIR}
src=${3:?usage: check_coverage.sh CC INCLUDE_DIRS SRCDIR}

# bind(C) interfaces deliberately without a wrapper in `use catchup`, each with why.
# Those marked "owed" are usable through module catchup_c / the module's c_
# interface today; their wrappers are owed (found by this check when it
# started to look, 2026-11).
RAW_ONLY=(
  cup_crowd_agents               # cup_crowd_t%agents holds N (set by cup_crowd_create)
  cup_crowd_q0                   # the caller passed q0 in and keeps it
  cup_crowd_radii                # owed
  cup_crowd_walls                # owed
  cup_crowd_gap                  # owed (a step's figures: the sink's ctx is the crowd)
  cup_crowd_rows                 # owed
  cup_crowd_added                # owed
  cup_crowd_desired_velocity     # owed
  cup_h5run_array                # owed
  cup_setproj_move               # the older C form; Fortran's cup_setproj_move calls cup_setproj_place
  cup_setproj_project            # the older C form; Fortran's cup_setproj_project calls cup_setproj_solve
  cup_scene_crowd                # owed (with the crowd's wrappers above)
)

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
bad=0
say() { echo "fortran coverage: $*"; bad=1; }

headers=()
for h in "$src"/include/catchup/*.h; do
  [ "$(basename "$h")" = export.h ] || headers+=("$h")
done
IFS=: read -ra dirs <<< "$incs"
for d in "${dirs[@]}"; do [ -f "$d/catchup/version.h" ] && headers+=("$d/catchup/version.h"); done
bash "$here/../layout/declared.sh" --args "$cc" "$incs" "${headers[@]}" | sort -u -k1,1 > "$work/declared" ||
  say "cannot list the public headers' functions"

fsrc=("$src"/src/fortran/*.f90 "$src"/src/fortran/*.F90)
# The generated interfaces, as the build makes them, of the headers a module includes.
gen=$(python3 "$src/src/fortran/gen_bindings.py" "$work/gen" "${headers[@]}" 2>&1) || say "$gen"
included=()
for f in $(sed -n 's/^ *include *"\(bind_[a-z0-9_]*\.inc\)".*/\1/p' "${fsrc[@]}" | sort -u); do
  [ -f "$work/gen/$f" ] && included+=("$work/gen/$f")
done
# "C_NAME FORTRAN_NAME NARGS" of every bind(C) interface (continuation lines
# joined; NARGS counts the names between the parentheses after its name)
awk '{ if (sub(/&[ \t]*$/, "")) { held = held $0; next } print held $0; held = "" }' "${fsrc[@]}" "${included[@]}" |
  sed -n 's/.*\(function\|subroutine\) *\([A-Za-z0-9_]*\) *(\([^)]*\)).*bind(C, *name="\(cup_[A-Za-z0-9_]*\)").*/\4 \2 \3/p' |
  awk '{ n = 0; for (i = 3; i <= NF; i++) n += split($i, a, ",") - ($i ~ /,$/); print $1, $2, n }' |
  sort -u > "$work/pairs3"
cut -d' ' -f1,2 "$work/pairs3" > "$work/pairs"
cut -d' ' -f1 "$work/pairs" | sort -u > "$work/bound"
PYTHONDONTWRITEBYTECODE=1 python3 -c 'import sys; sys.path.insert(0, sys.argv[1]); import gen_bindings; print("\n".join(gen_bindings.SKIP))' \
  "$src/src/fortran" | sort > "$work/unbound"
printf '%s\n' "${RAW_ONLY[@]}" | sort > "$work/raw_only"

while read -r name where _; do
  say "$where: $name has no bind(C) interface in src/fortran: include its header's" \
      "generated block (include \"bind_<header>.inc\") in its module, or put it on SKIP" \
      "in src/fortran/gen_bindings.py with why"
done < <(join -v1 "$work/declared" "$work/bound" | join -v1 - "$work/unbound")
while read -r name; do
  say "src/fortran binds $name (bind(C, name=\"$name\")), which no public header declares:" \
      "follow its rename or removal in C"
done < <(cut -d' ' -f1 "$work/declared" | join -v2 - "$work/bound")
while read -r name where cargs fname fargs; do
  say "$where: $name takes $cargs argument(s) in C, but its bind(C) interface $fname in src/fortran" \
      "takes $fargs: follow the C declaration (and the wrappers that call $fname)"
done < <(join "$work/declared" "$work/pairs3" | awk '$3 != $5')

# A wrapper: the interface itself under the C name (public, as cup_h5run_sink
# for c_funloc), or a reference to its Fortran name outside its own
# declaration (function/end lines, the public lists).
cat "${fsrc[@]}" > "$work/all.f90"
while read -r name fname; do
  if [ "$fname" = "$name" ]; then
    calls=1
  else
    calls=$(grep -i "\b$fname\b" "$work/all.f90" |
            grep -vi "^ *\(end \)\?\(function\|subroutine\) $fname\b\|public *::\|^ *[a-z0-9_, ]*&\? *$" |
            grep -ci "\b$fname\b")
  fi
  listed=$(grep -cx "$name" "$work/raw_only")
  if [ "$calls" = 0 ] && [ "$listed" = 0 ]; then
    say "$fname (bind(C) of $name) is used by no wrapper: add one to its module (as the" \
        "others there), or put it on RAW_ONLY in tests/fortran/check_coverage.sh with why"
  elif [ "$calls" != 0 ] && [ "$listed" != 0 ]; then
    say "RAW_ONLY lists $name, which a wrapper uses now: remove its line"
  fi
done < "$work/pairs"
while read -r name; do
  grep -qx "$name" "$work/bound" || say "RAW_ONLY lists $name, which is not bound: remove its line"
done < "$work/raw_only"

[ $bad = 0 ] && echo "fortran coverage: $(wc -l < "$work/declared") public functions:" \
  "$(wc -l < "$work/bound") bound in src/fortran, $(wc -l < "$work/unbound") on SKIP;" \
  "${#RAW_ONLY[@]} bound without a wrapper, on RAW_ONLY"
exit $bad
