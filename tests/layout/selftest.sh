#!/usr/bin/env bash
# The layout check itself: on copies of the tree it must pass as the tree is
# and fail, naming the culprit, on each injected violation: an include up the
# chain, a cycle inside a folder, a public header reaching into src/, a file
# outside the layers, src/ including apps/, a source file its folder's
# README.md does not name (a build file, a data file of tests/data too), a
# README line naming no file; and with objects, a
# call up the chain and a circle of calls behind includes that look innocent.
#
#   selftest.sh SRCDIR [CC]
set -u
here=$(cd "$(dirname "$0")" && pwd)
src=$1 cc=${2:-cc}
self=selftest
. "$here/expect.sh"
t=$work/t
fresh() { rm -rf "$t"; mkdir -p "$t"; cp -r "$src/src" "$src/apps" "$src/bench" "$src/include" "$t/"; }
check() { bash "$here/check.sh" "$t" "$@"; }   # check [OBJECT...]

fresh
bash "$here/check.sh" "$t" > /dev/null || fail "the tree as it is does not pass: $(bash "$here/check.sh" "$t")"

fresh
echo '#include "integrator/freestep.h"' >> "$t/src/set/polyset.c"
expect_fail "include up the chain" "src/set/polyset.c:"

fresh
sed -i 's|^#include "proj_ws.h"|#include "proj_ws.h"\n#include "firstorder.h"|' "$t/src/projector/certify.h"
expect_fail "cycle inside a folder" "cycle: "

fresh
echo '#include "set/polyset_impl.h"' >> "$t/include/catchup/polyset.h"
expect_fail "public header reaching into src/" "include/catchup/polyset.h:"

fresh
touch "$t/src/stray.c"
expect_fail "file outside the layers" "src/stray.c: not in a layer folder"

fresh
echo 'int app_helper(void);' > "$t/apps/app_helper.h"
echo '#include "../../apps/app_helper.h"' >> "$t/src/io/scene.c"
expect_fail "src/ including apps/" "src/io/scene.c:"

fresh
echo '/* a new reader */' > "$t/src/io/stray_reader.c"
expect_fail "file missing from its README" \
  'src/io/stray_reader.c: not named in src/io/README.md: add the line "- `stray_reader.c` — what it holds"'

fresh
sed -i '/^- `CMakeLists.txt`/d' "$t/apps/README.md"
expect_fail "build file missing from its README" 'apps/CMakeLists.txt: not named in apps/README.md'

fresh
mkdir -p "$t/tests" && cp -r "$src/tests/data" "$t/tests/"
printf 't,x\n' > "$t/tests/data/ref_new.csv"
expect_fail "data file missing from tests/data/README.md" 'tests/data/ref_new.csv: not named in tests/data/README.md'

fresh
echo '- `later.c` — later the netlist' >> "$t/src/model/README.md"
expect_fail "README naming no file" 'src/model/README.md: names `later.c`, which is not in src/model/'

# Objects: set/a calls projector/b (upward); projector/c and projector/d call
# each other (a circle); projector/e calls set/f (fine).
o=$work/obj
mkdir -p "$o/set" "$o/projector"
obj() { printf '%s\n' "$3" > "$work/$2.c" && "$cc" -c "$work/$2.c" -o "$o/$1/$2.c.o" || fail "cannot compile with $cc"; }
obj set a 'void b(void); void a(void) { b(); }'
obj projector b 'void b(void) {}'
obj projector c 'void d(void); void c(void) { d(); }'
obj projector d 'void c(void); void d(void) { c(); }'
obj projector e 'void f(void); void e(void) { f(); }'
obj set f 'void f(void) {}'
fresh
bash "$here/check.sh" "$t" "$o/projector/e.c.o;$o/set/f.c.o" > /dev/null ||
  fail "a call down the chain fails the check"
expect_fail "missing object" "no such object" "$o/set/none.c.o"
expect_fail "call up the chain" "calls b of src/projector/b" "$o/set/a.c.o" "$o/projector/b.c.o"
expect_fail "circle of calls" "cycle: src/projector/c -> src/projector/d -> src/projector/c" \
  "$o/projector/c.c.o;$o/projector/d.c.o"
echo "selftest: the layout check catches every injected violation"
