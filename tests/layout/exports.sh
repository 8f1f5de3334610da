#!/usr/bin/env bash
# What the shared libraries export is exactly what the public headers
# declare: `cup_` means public.
#
#   exports.sh CC INCLUDE_DIRS LIB=HEADER... [LIB=HEADER...]... [--internal SRCDIR ARCHIVE...]
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
#   * any exported symbol outside the cup_ prefix;
# and, after --internal, on an internal name carrying cup_ (cup_ means public;
# internal code prefixes its names by its module):
#   * a symbol named cup_* that a static ARCHIVE of the library's internal
#     code defines (nm --defined-only: functions, static ones too, and
#     variables) and no public header declares;
#   * a function, macro or type named cup_* that a file under SRCDIR declares
#     or defines at the start of a line (a function, static, inline or not, a
#     #define, a typedef, a struct) and no public header names.
# Prints one line per problem and exits 1 if there is any.
set -u
export LC_ALL=C   # sort and join agree on the order
cc=${1:?usage: exports.sh CC INCLUDE_DIRS LIB=HEADER[:HEADER...]...}
incs=${2:?usage: exports.sh CC INCLUDE_DIRS LIB=HEADER[:HEADER...]...}
shift 2
libs=() archives=() srcdir=""
while [ $# -gt 0 ]; do
  if [ "$1" = --internal ]; then srcdir=${2:?exports: --internal SRCDIR ARCHIVE...}; shift 2; archives=("$@"); break; fi
  libs+=("$1"); shift
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
bad=0
say() { echo "exports: $*"; bad=1; }
here=$(cd "$(dirname "$0")" && pwd)

total=0
: > "$work/alldecl"
for arg in "${libs[@]}"; do
  lib=${arg%%=*}
  name=$(basename "$lib")
  [ -f "$lib" ] || { say "$lib: no such library (build first)"; continue; }
  IFS=: read -ra headers <<< "${arg#*=}"
  bash "$here/declared.sh" "$cc" "$incs" "${headers[@]}" > "$work/decl" ||
    say "${headers[*]}: cannot list their declarations"
  sort -u -k1,1 "$work/decl" > "$work/decl.sorted"
  cut -d' ' -f1 "$work/decl" >> "$work/alldecl"
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

# --- cup_ means public: no internal name carries it ---------------------------
if [ -n "$srcdir" ]; then
  sort -u "$work/alldecl" > "$work/public"
  for a in "${archives[@]}"; do
    [ -f "$a" ] || { say "$a: no such archive (build first)"; continue; }
    while read -r sym obj; do
      say "$(basename "$a")($obj) defines $sym, an internal function named cup_ that no public" \
          "header declares: cup_ means public; give it its module's prefix (st_, nl_, la_, ...)"
    done < <(nm -A --defined-only "$a" 2>/dev/null |   # a clone (.cold, .constprop.0) as its function
             awk '{n = split($1, p, ":"); sym = $NF; sub(/\..*/, "", sym); if (sym ~ /^cup_/) print sym, p[n - 1]}' |
             sort -u -k1,1 | join -v1 - "$work/public")
  done
  # names the public headers (and the generated version.h) spell, types too
  IFS=: read -ra idirs <<< "$incs"
  for d in "${idirs[@]}"; do cat "$d"/catchup/*.h 2>/dev/null; done |
    grep -oE '\bcup_[A-Za-z0-9_]+' | sort -u > "$work/public_names"
  while IFS=: read -r file line name; do
    say "$file:$line: $name is defined here and named by no public header: cup_ means public;" \
        "give it its module's prefix"
  done < <(grep -rnoE --include='*.c' --include='*.h' \
             -e '^static\b.*\bcup_[A-Za-z0-9_]+[[:space:]]*\(' \
             -e '^[A-Za-z_][^;=(]*[[:space:]*]cup_[A-Za-z0-9_]+[[:space:]]*\(' \
             -e '^#[[:space:]]*define[[:space:]]+cup_[A-Za-z0-9_]+' \
             -e '^typedef[^;{]*\bcup_[A-Za-z0-9_]+[^;{]*;' \
             -e '^\}[[:space:]]*cup_[A-Za-z0-9_]+[[:space:]]*;' \
             -e '^(typedef[[:space:]]+)?(struct|union|enum)[[:space:]]+cup_[A-Za-z0-9_]+[[:space:]]*\{' "$srcdir" |
           perl -ne 'my ($f, $l, $m) = /^([^:]+):(\d+):(.*)$/ or next; my $n;
                     if ($m =~ /^#/) { ($n) = $m =~ /define\s+(cup_\w+)/ }
                     elsif ($m =~ /^(typedef|struct|union|enum|\})/) { $m =~ s/__attribute__.*//; ($n) = $m =~ /.*\b(cup_\w+)/ }
                     else { $m =~ s/__attribute__\s*\(\([^()]*\)\)//g; ($n) = $m =~ /^[^(]*\b(cup_\w+)\s*\(/ }
                     print "$f:$l:$n\n" if $n' |
           sort -t: -k3,3 | join -t: -1 3 -2 1 -v1 -o 1.1,1.2,1.3 - "$work/public_names")
fi

[ $bad = 0 ] && echo "exports: $total symbols exported by ${#libs[@]}" \
  "libraries, each declared by a public header with CUP_API, all cup_${srcdir:+; no internal name carries cup_}"
exit $bad
