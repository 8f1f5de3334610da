/* gen_constants — writes catchup_constants.f90, the Fortran named constants
 * of the C headers, at build time: the status codes come from the one
 * CUP_STATUS_LIST X-macro, the choice enums from theirs (CUP_SCHEME_LIST,
 * CUP_PROJ_METHOD_LIST, CUP_WAVE_LIST, CUP_OUTPUT_LIST, CUP_SET_LIST), the rest from their
 * C enumerators, so the Fortran numbers are the compiler's and cannot drift
 * from the headers.
 *
 *   gen_constants OUT.f90 */
#include <stdio.h>
#include <string.h>
#include "catchup.h"

#define CONST(f, name) fprintf(f, "  integer(c_int), parameter, public :: %s = %d\n", #name, (int)(name))

static void status_table(FILE *f) {
  int count = 0;
#define COUNT_(name, value, text) count++;
  CUP_STATUS_LIST(COUNT_)
#undef COUNT_
  fprintf(f, "\n  ! status codes (include/catchup/status.h, CUP_STATUS_LIST)\n");
#define CONST_(name, value, text) CONST(f, name);
  CUP_STATUS_LIST(CONST_)
#undef CONST_
  fprintf(f, "  !> number of status codes, and every code with its name, in list order\n");
  fprintf(f, "  integer, parameter, public :: CUP_STATUS_COUNT = %d\n", count);
  fprintf(f, "  integer(c_int), parameter, public :: CUP_STATUS_CODES(%d) = [ &\n", count);
  int i = 0;
#define CODE_(name, value, text) fprintf(f, "    %s%s\n", #name, ++i < count ? ", &" : "]");
  CUP_STATUS_LIST(CODE_)
#undef CODE_
  size_t width = 0;
#define WIDTH_(name, value, text) if (strlen(#name) > width) width = strlen(#name);
  CUP_STATUS_LIST(WIDTH_)
#undef WIDTH_
  fprintf(f, "  character(len=%zu), parameter, public :: CUP_STATUS_NAMES(%d) = [character(len=%zu) :: &\n",
          width, count, width);
  i = 0;
#define NAME_(name, value, text) fprintf(f, "    \"%s\"%s\n", #name, ++i < count ? ", &" : "]");
  CUP_STATUS_LIST(NAME_)
#undef NAME_
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: gen_constants OUT.f90\n");
    return 2;
  }
  FILE *f = fopen(argv[1], "w");
  if (!f) {
    perror(argv[1]);
    return 1;
  }
  fprintf(f, "! catchup_constants.f90 -- GENERATED at build time by src/fortran/gen_constants.c\n"
             "! from the C headers; do not edit. Every value is the C compiler's.\n"
             "module catchup_constants\n"
             "  use, intrinsic :: iso_c_binding, only: c_int\n"
             "  implicit none\n"
             "  private\n");

  fprintf(f, "\n  ! version (include/catchup/version.h, of the headers the module was built from)\n");
  CONST(f, CUP_VERSION_MAJOR);
  CONST(f, CUP_VERSION_MINOR);
  CONST(f, CUP_VERSION_PATCH);
  CONST(f, CUP_VERSION_NUMBER);
  fprintf(f, "  character(len=*), parameter, public :: CUP_VERSION_STRING = \"%s\"\n", CUP_VERSION_STRING);

  fprintf(f, "\n  ! length of the error-message buffers (include/catchup/sparse.h)\n");
  CONST(f, CUP_ERRMSG_LEN);
  fprintf(f, "  ! length of cup_run_info%%message (include/catchup/sparse.h)\n");
  CONST(f, CUP_RUN_MSG_LEN);

  status_table(f);

  fprintf(f, "\n  ! enum cup_metric_kind (polyset.h)\n");
  CONST(f, CUP_METRIC_IDENTITY);
  CONST(f, CUP_METRIC_DIAGONAL);
  CONST(f, CUP_METRIC_SPARSE);
  /* the choice lists: every enumerator and the count, from the one list */
#define CONST4_(e, v, name, doc) CONST(f, e);
#define CONST5_(e, v, name, form, doc) CONST(f, e);
  fprintf(f, "\n  ! enum cup_proj_method (projector.h, CUP_PROJ_METHOD_LIST)\n");
  CUP_PROJ_METHOD_LIST(CONST4_)
  CONST(f, CUP_PROJ_METHOD_COUNT);
  fprintf(f, "\n  ! enum cup_wave_kind (input.h, CUP_WAVE_LIST)\n");
  CUP_WAVE_LIST(CONST4_)
  CONST(f, CUP_WAVE_COUNT);
  fprintf(f, "\n  ! enum cup_scheme (integrator.h, CUP_SCHEME_LIST)\n");
  CUP_SCHEME_LIST(CONST4_)
  CONST(f, CUP_SCHEME_COUNT);
  fprintf(f, "\n  ! enum cup_output_kind (integrator.h, CUP_OUTPUT_LIST)\n");
  CUP_OUTPUT_LIST(CONST5_)
  CONST(f, CUP_OUTPUT_COUNT);
  fprintf(f, "\n  ! enum cup_set_kind (set.h, CUP_SET_LIST)\n");
  CUP_SET_LIST(CONST4_)
  CONST(f, CUP_SET_COUNT);
  fprintf(f, "\n  ! cup_pss_options%%jacobian (pss.h)\n");
  CONST(f, CUP_PSS_JACOBIAN_AUTO);
  CONST(f, CUP_PSS_JACOBIAN_FD);
  CONST(f, CUP_PSS_MAX_ITER);
#undef CONST4_
#undef CONST5_

  fprintf(f, "end module catchup_constants\n");
  if (fclose(f) != 0) {
    perror(argv[1]);
    return 1;
  }
  return 0;
}
