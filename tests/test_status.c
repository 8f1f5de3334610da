/* Status table and version: the enum, names and messages come from one list. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>
#include "catchup.h"

/* The documented numbers (README, HDF5 /summary) written out independently. */
static const struct { int value; const char *name; } documented[] = {
  {0, "CUP_OK"}, {-1, "CUP_ERR_NOMEM"}, {-2, "CUP_ERR_ARG"}, {-3, "CUP_ERR_DIM"},
  {-4, "CUP_ERR_NONFINITE"}, {-5, "CUP_ERR_NOT_SPD"}, {-6, "CUP_ERR_EMPTY_SET"},
  {-7, "CUP_ERR_PB_CT"}, {-8, "CUP_ERR_CALLBACK"}, {-9, "CUP_ERR_DIVERGED"},
  {-10, "CUP_ERR_IO"}, {-11, "CUP_ERR_PARSE"}, {-12, "CUP_ERR_LINALG"},
  {-13, "CUP_ERR_TIME_LIMIT"}, {-14, "CUP_ERR_INTERRUPTED"},
  {-15, "CUP_ERR_UNSUPPORTED"}, {1, "CUP_WARN_NOT_CERTIFIED"},
  {2, "CUP_WARN_STIFF"}, {3, "CUP_WARN_QUADRATURE"}, {4, "CUP_WARN_X0_OUTSIDE"},
  {5, "CUP_WARN_SPLITTING"},
};
#define NDOC (sizeof documented / sizeof documented[0])

static void test_names_match_documented_numbers(void **state) {
  (void)state;
  for (size_t i = 0; i < NDOC; i++)
    assert_string_equal(cup_status_name(documented[i].value), documented[i].name);
}

static void test_messages_distinct_and_nonempty(void **state) {
  (void)state;
  for (size_t i = 0; i < NDOC; i++) {
    const char *a = cup_status_string(documented[i].value);
    assert_true(strlen(a) > 1);
    assert_string_not_equal(a, "unknown status");
    for (size_t j = i + 1; j < NDOC; j++)
      assert_string_not_equal(a, cup_status_string(documented[j].value));
  }
}

static void test_unknown_codes(void **state) {
  (void)state;
  assert_string_equal(cup_status_string(-9999), "unknown status");
  assert_string_equal(cup_status_name(4242), "CUP_UNKNOWN");
}

static void test_sign_convention(void **state) {
  (void)state;
  assert_int_equal(CUP_OK, 0);
  assert_true(CUP_ERR_EMPTY_SET < 0);
  assert_true(CUP_WARN_NOT_CERTIFIED > 0);
}

static void test_merge_keeps_most_severe(void **state) {
  (void)state;
  assert_int_equal(cup_status_merge(CUP_OK, CUP_OK), CUP_OK);
  assert_int_equal(cup_status_merge(CUP_OK, CUP_WARN_STIFF), CUP_WARN_STIFF);
  assert_int_equal(cup_status_merge(CUP_WARN_STIFF, CUP_WARN_NOT_CERTIFIED), CUP_WARN_STIFF);
  assert_int_equal(cup_status_merge(CUP_WARN_STIFF, CUP_ERR_IO), CUP_ERR_IO);
  assert_int_equal(cup_status_merge(CUP_ERR_DIM, CUP_ERR_IO), CUP_ERR_DIM);
}

static void test_version_matches_build(void **state) {
  (void)state;
  /* CUP_TEST_PROJECT_VERSION comes from CMake's project(), not from our header. */
  assert_string_equal(cup_version(), CUP_TEST_PROJECT_VERSION);
  assert_string_equal(CUP_VERSION_STRING, CUP_TEST_PROJECT_VERSION);
  assert_int_equal(CUP_VERSION_NUMBER,
                   CUP_VERSION_MAJOR * 10000 + CUP_VERSION_MINOR * 100 + CUP_VERSION_PATCH);
}

static void test_dependency_versions(void **state) {
  (void)state;
  char buf[256], tiny[8];
  int need = cup_dependency_versions(buf, sizeof buf);
  assert_int_equal(need, (int)strlen(buf));
  assert_non_null(strstr(buf, "CHOLMOD "));
  assert_non_null(strstr(buf, "GSL 2."));
  assert_non_null(strstr(buf, "libyaml 0."));
  /* Truncation follows snprintf: same length reported, terminated buffer. */
  assert_int_equal(cup_dependency_versions(tiny, sizeof tiny), need);
  assert_int_equal(strlen(tiny), sizeof tiny - 1);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_names_match_documented_numbers),
    cmocka_unit_test(test_messages_distinct_and_nonempty),
    cmocka_unit_test(test_unknown_codes),
    cmocka_unit_test(test_sign_convention),
    cmocka_unit_test(test_merge_keeps_most_severe),
    cmocka_unit_test(test_version_matches_build),
    cmocka_unit_test(test_dependency_versions),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
