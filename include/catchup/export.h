/* catchup/export.h — CUP_API marks a function of the public API.
 *
 * The library is built with -fvisibility=hidden: a function is exported from
 * libcatchup.so (and libcatchup_h5.so) only if its declaration in a public
 * header starts with CUP_API, and everything else the library's files share
 * stays inside it. A public function declared without CUP_API is not
 * exported: a program calling it fails to link against the shared library
 * ("undefined reference to cup_..."), and `ctest -L layout` (the exports
 * test) names the header line to mend. For the static library (CMake target
 * catchup::catchup_static, which defines CUP_STATIC for its users) the macro
 * is empty. */
#ifndef CATCHUP_EXPORT_H
#define CATCHUP_EXPORT_H

#if defined(CUP_STATIC) || !(defined(__GNUC__) || defined(__clang__))
#define CUP_API
#else
#define CUP_API __attribute__((visibility("default")))
#endif

#endif
