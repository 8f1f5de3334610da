#!/usr/bin/env bash
# The Fortran drift check itself: on a copy of the tree it must pass as the
# tree is, and fail, naming the culprit, on a new public function no wrapper
# uses (generated, but not offered by `use catchup`), a new one the
# generator cannot map, a header whose generated block no module includes,
# an annotation of a parameter C renamed, a binding written by hand of a
# function C no longer declares, and a binding no wrapper uses.
#
#   check_coverage_selftest.sh CC SRCDIR BUILD_INCLUDE_DIR
set -u
here=$(cd "$(dirname "$0")" && pwd)
cc=$1 src=$2 binc=$3
self=check_coverage_selftest
. "$here/../layout/expect.sh"
t=$work/t
fresh() { rm -rf "$t"; mkdir -p "$t/src"; cp -r "$src/include" "$t/"; cp -r "$src/src/fortran" "$t/src/"; }
check() { bash "$here/check_coverage.sh" "$cc" "$t/include:$binc" "$t"; }

fresh
check > /dev/null || fail "the tree as it is fails: $(check)"

fresh
sed -i 's|^CUP_API int cup_lcs_dim(|CUP_API int cup_lcs_brand_new(const cup_lcs *L);\n&|' "$t/include/catchup/lcs.h"
expect_fail "new public function, no wrapper" "c_cup_lcs_brand_new (bind(C) of cup_lcs_brand_new) is used by no wrapper"

fresh
sed -i 's|^CUP_API int cup_lcs_dim(|CUP_API int cup_lcs_brand_new(const cup_lcs *L, float *q);\n&|' "$t/include/catchup/lcs.h"
expect_fail "new public function the generator cannot map" \
  'cup_lcs_brand_new: parameter "float* q" has no Fortran mapping'

fresh
sed -i '/include "bind_lcs.inc"/d' "$t/src/fortran/catchup_c.f90"
expect_fail "a header's block included by no module" "cup_lcs_rows has no bind(C) interface"

fresh
sed -i 's|^CUP_API int cup_polyset_contains(const cup_polyset \*K, const double \*g,|CUP_API int cup_polyset_contains(const cup_polyset *K, const double *h,|' \
  "$t/include/catchup/polyset.h"
expect_fail "annotated parameter renamed in C" 'cup_polyset_contains: ANNOTATE names "g", which is no parameter of it'

fresh
printf '%s\n' 'module gone' 'interface' \
  '  function c_cup_gone(k) bind(C, name="cup_gone") result(r)' 'end interface' 'end module gone' \
  > "$t/src/fortran/gone.f90"
expect_fail "binding of a function C no longer declares" "binds cup_gone (bind(C, name=\"cup_gone\")), which no public header declares"

fresh
sed -i 's|c_cup_lcs_has_D(L%ptr) /= 0|.false.|' "$t/src/fortran/catchup_model.f90"
expect_fail "binding no wrapper uses" "c_cup_lcs_has_D (bind(C) of cup_lcs_has_D) is used by no wrapper"
echo "check_coverage_selftest: the drift check catches every injected drift"
