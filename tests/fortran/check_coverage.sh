#!/usr/bin/env bash
# The Fortran module cannot silently fall behind the C API (src/fortran is
# written by hand; docs/design.md says why). Fails, naming the function and
# what to do, when
#   * a function of the public headers has no bind(C) interface in
#     src/fortran and is not on the list UNBOUND below;
#   * a bind(C) interface names no public function (one that was renamed or
#     removed in C);
#   * a bind(C) interface takes more or fewer arguments than the C function
#     declares (a parameter added or removed in C: the call would pass
#     garbage or drop one, silently);
#   * a bind(C) interface is never called by a wrapper (c_cup_x declared but
#     unused: `use catchup` does not offer it) and is not on RAW_ONLY;
#   * an entry of either list no longer applies.
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

# Public functions deliberately without a bind(C) interface, each with why.
UNBOUND=(
  cup_status_merge   # restated in Fortran as an elemental function (catchup_base.f90)
  cup_netlist_switching            # a table of C function pointers; a scene's integrator (cup_scene_integrator) runs switches
  cup_integrator_create_switched   # takes that table; Fortran reaches it through cup_scene_integrator
  cup_scene_steady_state   # catchup-run's request (scene key steady_state:); Fortran sets cup_pss_options itself
)
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
# "C_NAME FORTRAN_NAME NARGS" of every bind(C) interface (continuation lines
# joined; NARGS counts the names between the parentheses after its name)
awk '{ if (sub(/&[ \t]*$/, "")) { held = held $0; next } print held $0; held = "" }' "${fsrc[@]}" |
  sed -n 's/.*\(function\|subroutine\) *\([A-Za-z0-9_]*\) *(\([^)]*\)).*bind(C, *name="\(cup_[A-Za-z0-9_]*\)").*/\4 \2 \3/p' |
  awk '{ n = 0; for (i = 3; i <= NF; i++) n += split($i, a, ",") - ($i ~ /,$/); print $1, $2, n }' |
  sort -u > "$work/pairs3"
cut -d' ' -f1,2 "$work/pairs3" > "$work/pairs"
cut -d' ' -f1 "$work/pairs" | sort -u > "$work/bound"
printf '%s\n' "${UNBOUND[@]}" | sort > "$work/unbound"
printf '%s\n' "${RAW_ONLY[@]}" | sort > "$work/raw_only"

while read -r name where _; do
  say "$where: $name has no bind(C) interface in src/fortran: bind it (catchup_c.f90 or" \
      "its module's file, with a wrapper in the conventions of catchup_base.f90), or put it" \
      "on UNBOUND in tests/fortran/check_coverage.sh with why"
done < <(join -v1 "$work/declared" "$work/bound" | join -v1 - "$work/unbound")
while read -r name; do
  say "src/fortran binds $name (bind(C, name=\"$name\")), which no public header declares:" \
      "follow its rename or removal in C"
done < <(cut -d' ' -f1 "$work/declared" | join -v2 - "$work/bound")
while read -r name where cargs fname fargs; do
  say "$where: $name takes $cargs argument(s) in C, but its bind(C) interface $fname in src/fortran" \
      "takes $fargs: follow the C declaration (and the wrappers that call $fname)"
done < <(join "$work/declared" "$work/pairs3" | awk '$3 != $5')
while read -r name; do
  say "UNBOUND lists $name, which is bound now or no longer declared: remove its line"
done < <(join -v1 "$work/unbound" <(cut -d' ' -f1 "$work/declared" | join -v1 - "$work/bound"))

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
  "$(wc -l < "$work/bound") bound in src/fortran, ${#UNBOUND[@]} on UNBOUND;" \
  "${#RAW_ONLY[@]} bound without a wrapper, on RAW_ONLY"
exit $bad
