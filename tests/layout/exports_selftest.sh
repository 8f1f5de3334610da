#!/usr/bin/env bash
# The exports check itself: on a small library and header made here it must
# pass as they are, and fail, naming the symbol, when the library exports a
# helper outside cup_ (built without -fvisibility=hidden), when an internal
# cup_ function carries CUP_API, when a public declaration lacks CUP_API, and
# (--internal) when an internal function, static inline or type is named cup_.
#
#   exports_selftest.sh SRCDIR [CC]
set -u
here=$(cd "$(dirname "$0")" && pwd)
src=$1 cc=${2:-cc}
self=exports_selftest
. "$here/expect.sh"

mkdir -p "$work/inc/catchup"
cp "$src/include/catchup/export.h" "$work/inc/catchup/"
header() {   # header API_BETA: writes the public header, CUP_API on cup_beta or not
  cat > "$work/inc/catchup/fake.h" <<HDR
#include "catchup/export.h"
CUP_API int cup_alpha(void);
$1 int cup_beta(int k);
static inline int cup_gamma(void) { return 3; }
HDR
}
lib() {   # lib NAME EXTRA_SOURCE [CFLAGS...]: the library defining the header's functions
  local name=$1 extra=$2
  shift 2
  printf '#include "catchup/fake.h"\nint st_helper(int k) { return k + 1; }\n%s\n%s\n%s\n' \
    'int cup_alpha(void) { return st_helper(1); }' 'int cup_beta(int k) { return st_helper(k); }' \
    "$extra" > "$work/$name.c"
  "$cc" -shared -fPIC "$@" -I"$work/inc" "$work/$name.c" -o "$work/$name.so" ||
    fail "cannot build $name.so with $cc"
}
check() { bash "$here/exports.sh" "$cc" "$work/inc" "$work/$1.so=$work/inc/catchup/fake.h"; }   # check LIB

header CUP_API
lib good 'int cup_internal(void) { return 2; }' -fvisibility=hidden
check good > /dev/null || fail "a clean library fails the check: $(check good)"
lib leaky '' 
expect_fail "helper exported outside cup_ (no -fvisibility=hidden)" "exports st_helper, outside the cup_ prefix" leaky
lib internal 'CUP_API int cup_rowpool_init(void) { return 2; }' -fvisibility=hidden
expect_fail "internal cup_ function with CUP_API" "exports cup_rowpool_init, which no public header" internal
# --internal: the archive of the internal code and its sources
internal() {   # internal NAME EXTRA_SOURCE EXTRA_HEADER: an archive and a src/ folder
  local name=$1
  mkdir -p "$work/$name/src"
  printf '#include "catchup/fake.h"\n#include "mod.h"\nint st_helper(int k) { return st_min(k, 1); }\n%s\n%s\n%s\n' \
    'int cup_alpha(void) { return st_helper(1); }' 'int cup_beta(int k) { return st_helper(k); }' \
    "$2" > "$work/$name/src/mod.c"
  printf 'static inline int st_min(int a, int b) { return a < b ? a : b; }\n%s\n' "$3" > "$work/$name/src/mod.h"
  "$cc" -c -fvisibility=hidden -I"$work/inc" "$work/$name/src/mod.c" -o "$work/$name/mod.o" &&
    ar rc "$work/$name/libmod.a" "$work/$name/mod.o" || fail "cannot build $name/libmod.a with $cc"
}
check_internal() {   # check_internal NAME: the shared library good.so, the archive and sources of NAME
  bash "$here/exports.sh" "$cc" "$work/inc" "$work/good.so=$work/inc/catchup/fake.h" \
    --internal "$work/$1/src" "$work/$1/libmod.a"
}
internal clean '' 'typedef struct st_pool { int n; } st_pool;'
check_internal clean > /dev/null || fail "clean internal code fails the check: $(check_internal clean)"
check() { check_internal "$@"; }
internal named 'int cup_rowpool_init(void) { return 2; }' ''
expect_fail "internal function named cup_" "defines cup_rowpool_init, an internal function named cup_" named
internal inline '' 'static inline int cup_min(int a, int b) { return a < b ? a : b; }'
expect_fail "internal static inline named cup_" "mod.h:2: cup_min is defined here" inline
internal type '' 'typedef struct cup_pool { int n; } cup_pool;'
expect_fail "internal type named cup_" "mod.h:2: cup_pool is defined here" type
check() { bash "$here/exports.sh" "$cc" "$work/inc" "$work/$1.so=$work/inc/catchup/fake.h"; }

header ''
lib nomacro '' -fvisibility=hidden
expect_fail "public declaration without CUP_API" "fake.h:3: cup_beta is declared but nomacro.so does not export it: write CUP_API" nomacro
echo "exports_selftest: the exports check catches every injected violation"
