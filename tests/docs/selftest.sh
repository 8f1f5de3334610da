#!/usr/bin/env bash
# The docs runner must fail what it is there to catch: a block that fails,
# a command left in an indented block, a skip without its reason, a sub
# that matches nothing; and pass a good block, a skipped one and a shrunk one.
#   selftest.sh PYTHON3 run_docs.py SOURCE BUILD
set -u
py=$1 runner=$2 src=$3 build=$4
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0
expect() {   # expect PASS|FAIL NAME CONTENT
  printf '%s\n' "$3" > "$tmp/$2.md"
  out=$("$py" "$runner" --source "$src" --build "$build" "$tmp/$2.md" 2>&1); rc=$?
  if { [ "$1" = PASS ] && [ $rc -ne 0 ]; } || { [ "$1" = FAIL ] && [ $rc -ne 1 ]; }; then
    echo "docs_selftest: $2: expected $1, got exit $rc:"; echo "$out"; fails=$((fails + 1))
  else
    echo "docs_selftest: $2: $1 as expected"
  fi
}
fence='```'
expect PASS good "$(printf 'text\n\n%ssh\nbuild/apps/catchup-run --help > /dev/null || test $? -eq 2\n%s\n' "$fence" "$fence")"
expect FAIL failing "$(printf 'text\n\n%sbash\nfalse\n%s\n' "$fence" "$fence")"
expect FAIL second-line "$(printf '%ssh\ntrue\nls no-such-file\n%s\n' "$fence" "$fence")"
expect FAIL indented "$(printf 'text\n\n    build/apps/catchup-run examples/paper-fig2.yaml -o x.h5\n')"
expect PASS indented-output "$(printf 'text\n\n    catchup-run: x.yaml -> x.h5: n=100 explicit\n')"
expect FAIL skip-no-reason "$(printf '<!-- docs-test: skip -->\n%ssh\ntrue\n%s\n' "$fence" "$fence")"
expect PASS skipped "$(printf '<!-- docs-test: skip it would fail -->\n%ssh\nfalse\n%s\n' "$fence" "$fence")"
expect FAIL sub-nomatch "$(printf '<!-- docs-test: sub nothing => x -->\n%ssh\ntrue\n%s\n' "$fence" "$fence")"
expect PASS sub "$(printf '<!-- docs-test: sub false => true -->\n%ssh\nfalse\n%s\n' "$fence" "$fence")"
expect PASS console "$(printf '%sconsole\n$ echo hi\nhi\n%s\n' "$fence" "$fence")"
expect FAIL timeout "$(printf '<!-- docs-test: timeout 1 -->\n%ssh\nsleep 5\n%s\n' "$fence" "$fence")"
[ $fails -eq 0 ] && echo "docs_selftest: 11 passed, 0 failed" || { echo "docs_selftest: $fails failed"; exit 1; }
