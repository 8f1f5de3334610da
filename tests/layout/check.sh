#!/usr/bin/env bash
# Dependencies run one way, down the paper's chain:
#
#     util < set < lcp < projector < model < integrator < analysis < io < h5 < sweep < apps, fortran, bench
#
# A file may include (and its object may call) only its own folder and the
# folders below it; the public headers (include/) may be included by any
# file and include nothing of src/. Within the graph of modules (a module is
# a .c with its .h of the same name), there must be no cycle, in a folder
# too: a method includes a header below the dispatcher, never the
# dispatcher's.
#
#   check.sh SRCDIR [OBJECT...]
#
# Reads every `#include "..."` of src/, apps/ and include/, resolved as the
# build resolves them (the including file's folder, src/, include/, then a
# folder of src/ that a library exports). With object files (the libraries'
# .o, named FOLDER/NAME.c.o; a ;-separated list is split), the symbols each
# one uses from the others must follow the same order and form no cycle
# either: that catches a call upward or a circle behind a shared header.
# And the map: every source and build file (.c, .h, .h.in, .f90, .F90,
# .cmake, CMakeLists.txt, .py, .sh) of a folder with a README.md (src/*/,
# apps/, bench/, include/), and every file of tests/data/, has its line
# there, "- `NAME` — what it holds" (or a table row "| `NAME` | ..."), and
# every such line names a file that exists.
# Prints one line per violation and exits 1 if there is any.
set -u
order=(util set lcp projector model integrator analysis io h5 sweep apps)
declare -A level=([util]=0 [set]=1 [lcp]=2 [projector]=3 [model]=4 [integrator]=5 [analysis]=6 [io]=7
                  [h5]=8 [sweep]=9 [apps]=10 [fortran]=10 [bench]=10)
generated=" catchup/version.h git_revision.h "   # written into the build tree

root=${1:?usage: check.sh SRCDIR [OBJECT...]}
shift
cd "$root" || exit 2
bad=0
say() { echo "layout: $*"; bad=1; }

# The folder (a key of level), "public", or "" for a file outside the layers.
folder_of() {
  case $1 in
    include/*) echo public ;;
    apps/*) echo apps ;;
    bench/*) echo bench ;;
    src/*/*) local f=${1#src/}; f=${f%%/*}; [ -n "${level[$f]+x}" ] && echo "$f" ;;
  esac
}

# Where `#include "name"` in file $1 lands, relative to the root, or "".
resolve() {
  local from=$1 name=$2 d
  for d in "$(dirname "$from")" src include; do
    [ -f "$d/$name" ] && { realpath --relative-to=. -m "$d/$name"; return; }
  done
  local hits=(src/*/"$name")
  [ ${#hits[@]} -eq 1 ] && [ -f "${hits[0]}" ] && echo "${hits[0]}"
}

declare -A deps=()   # module -> space-separated modules it needs
module_of() { local m=${1%.c}; echo "${m%.h}"; }
add_dep() { [ "$1" != "$2" ] && [[ " ${deps[$1]:-} " != *" $2 "* ]] && deps[$1]+=" $2"; }

mapfile -t files < <(find src apps bench include -name '*.[ch]' -type f 2>/dev/null | sort)
for f in "${files[@]}"; do
  ff=$(folder_of "$f")
  if [ -z "$ff" ]; then
    say "$f: not in a layer folder (src/{$(IFS=,; echo "${order[*]}"),fortran}/, apps/, bench/, include/)"
    continue
  fi
  while IFS=: read -r line name; do
    name=${name#*\"}; name=${name%%\"*}
    [[ $generated == *" $name "* ]] && continue
    t=$(resolve "$f" "$name")
    if [ -z "$t" ]; then say "$f:$line: #include \"$name\" is not found"; continue; fi
    tf=$(folder_of "$t")
    if [ "$tf" = public ]; then continue; fi
    if [ "$ff" = public ]; then
      say "$f:$line: the public header includes $t (internal)"
    elif [ -z "$tf" ]; then
      say "$f:$line: includes $t, outside the layer folders"
    elif [ "${level[$tf]}" -gt "${level[$ff]}" ]; then
      say "$f:$line: $ff/ includes $t, a layer above it (order: ${order[*]})"
    else
      add_dep "$(module_of "$f")" "$(module_of "$t")"
    fi
  done < <(grep -n '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' "$f")
done

# The map: a folder's README.md names each of its files on a line of its
# own, "- `NAME` — ..." or a table row "| `NAME` | ..." (NAME relative to
# the folder), and nothing else.
for d in src/*/ apps/ bench/ include/ tests/data/; do
  d=${d%/}
  readme=$d/README.md
  [ -f "$readme" ] || { [ -d "$d" ] && say "$d/: has no README.md naming its files"; continue; }
  if [ "$d" = tests/data ]; then
    which=(! -name README.md)                                  # data: every file
  else
    which=(\( -name '*.[ch]' -o -name '*.h.in' -o -name '*.[fF]90' -o -name '*.cmake' -o -name CMakeLists.txt
           -o -name '*.py' -o -name '*.sh' \))
  fi
  while read -r f; do
    rel=${f#"$d"/}
    grep -qF -e "- \`$rel\`" -e "| \`$rel\` |" "$readme" ||
      say "$f: not named in $readme: add the line \"- \`$rel\` — what it holds\" (one line per file)"
  done < <(find "$d" "${which[@]}" -type f | sort)
  while read -r rel; do
    [ -f "$d/$rel" ] || say "$readme: names \`$rel\`, which is not in $d/: remove or mend its line"
  done < <(sed -n 's/^\(- \|| \)`\([^`]*\)`.*/\2/p' "$readme")
done

# Objects: FOLDER/NAME.c.o; an undefined symbol defined by another object is
# an edge to that object's module.
objects=()
for a in "$@"; do IFS=';' read -ra parts <<< "$a"; objects+=("${parts[@]}"); done
if [ ${#objects[@]} -gt 0 ]; then
  declare -A owner=() omod=()
  for o in "${objects[@]}"; do
    [ -f "$o" ] || { say "$o: no such object (build first)"; continue; }
    base=$(basename "$o" .c.o); dir=$(basename "$(dirname "$o")")
    if [ -z "${level[$dir]+x}" ]; then say "$o: object outside the layer folders"; continue; fi
    omod[$o]="src/$dir/$base"
    while read -r _ kind sym; do
      case $kind in [TDBR]) owner[$sym]=${omod[$o]} ;; esac
    done < <(nm -P --defined-only "$o" 2>/dev/null | awk '{print "x", $2, $1}')
  done
  for o in "${!omod[@]}"; do
    m=${omod[$o]}; mf=${m#src/}; mf=${mf%%/*}
    while read -r sym; do
      t=${owner[$sym]:-}
      [ -z "$t" ] || [ "$t" = "$m" ] && continue
      tf=${t#src/}; tf=${tf%%/*}
      if [ "${level[$tf]}" -gt "${level[$mf]}" ]; then
        say "$o: calls $sym of $t, a layer above $mf/ (order: ${order[*]})"
      else
        add_dep "$m" "$t"
      fi
    done < <(nm -P --undefined-only "$o" 2>/dev/null | awk '{print $1}')
  done
fi

# Cycles among modules: depth-first search, grey = on the current path.
declare -A colour=()
path=()
visit() {
  local m=$1 n
  colour[$m]=grey; path+=("$m")
  for n in ${deps[$m]:-}; do
    if [ "${colour[$n]:-}" = grey ]; then
      local cyc="" p on=0
      for p in "${path[@]}"; do [ "$p" = "$n" ] && on=1; [ $on = 1 ] && cyc+="$p -> "; done
      say "cycle: $cyc$n"
    elif [ -z "${colour[$n]:-}" ]; then
      visit "$n"
    fi
  done
  colour[$m]=black; unset 'path[${#path[@]}-1]'
}
for m in $(printf '%s\n' "${!deps[@]}" | sort); do
  [ -z "${colour[$m]:-}" ] && visit "$m"
done

[ $bad = 0 ] && echo "layout: ${#files[@]} files${objects:+, ${#objects[@]} objects}: every dependency runs down ${order[*]}, no cycle"
exit $bad
