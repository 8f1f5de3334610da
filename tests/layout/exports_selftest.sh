#!/usr/bin/env bash
# The exports check itself: on a small library and header made here it must
# pass as they are, and fail, naming the symbol, when the library exports a
# helper outside cup_ (built without -fvisibility=hidden), when an internal
# cup_ function carries CUP_API, and when a public declaration lacks CUP_API.
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
header ''
lib nomacro '' -fvisibility=hidden
expect_fail "public declaration without CUP_API" "fake.h:3: cup_beta is declared but nomacro.so does not export it: write CUP_API" nomacro
echo "exports_selftest: the exports check catches every injected violation"
