# Sourced by the checks' selftests (layout, exports, Fortran coverage): the
# includer sets `self` (its name in messages) and defines check ARG..., which
# runs the check under test on the injected tree.
#   work                      a scratch folder, removed on exit
#   fail TEXT                 say TEXT and exit 1
#   expect_fail WHAT TEXT [ARG...]
#                             check ARG... must fail, and name TEXT
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "$self: $*"; exit 1; }
expect_fail() {
  local what=$1 text=$2 out
  shift 2
  out=$(check "$@" 2>&1) && fail "$what: the check passed, expected a failure"
  grep -qF -- "$text" <<< "$out" || fail "$what: the check failed without naming '$text': $out"
  echo "$self: $what: caught"
}
