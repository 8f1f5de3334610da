/* Status code table: strings generated from the same list as the enum. */
#include "catchup.h"

const char *cup_status_string(int status) {
  switch (status) {
#define CUP_STATUS_CASE_(name, value, text) case value: return text;
    CUP_STATUS_LIST(CUP_STATUS_CASE_)
#undef CUP_STATUS_CASE_
  }
  return "unknown status";
}

const char *cup_status_name(int status) {
  switch (status) {
#define CUP_STATUS_CASE_(name, value, text) case value: return #name;
    CUP_STATUS_LIST(CUP_STATUS_CASE_)
#undef CUP_STATUS_CASE_
  }
  return "CUP_UNKNOWN";
}

int cup_status_merge(int first, int second) {
  if (first < 0) return first;
  if (second < 0) return second;
  return first > 0 ? first : second;
}
