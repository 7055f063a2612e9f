#!/usr/bin/env bash
# Runs cmocka test programs and prints one closing line "N passed, M failed, K skipped": the programs named
# (`make test`, `make check`), or every test_* program in a folder (default build/san/tests). A folder named
# tests/python is the Python package's pytest suite, run with $PYTHON (default /usr/bin/python3) against the
# package built in build/python, and counted alike.
# A skipped test (cmocka's skip(): e.g. the paper's scenes are not beside the checkout) is named with the
# reason it printed and is not a failure. Exit status 0 iff nothing failed and something passed.
set -u
if [ $# -eq 0 ] || { [ $# -eq 1 ] && [ -d "$1" ] && [ "${1%python}" = "$1" ]; }; then
  set -- "${1:-build/san/tests}"/test_*
fi
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export CMOCKA_MESSAGE_OUTPUT=stdout
passed=0; failed=0; skipped=0; broken=""
start=$(date +%s)
# pytest's summary line "== 3 passed, 1 failed, 2 skipped in 4.1s ==": count of one outcome
count() { printf '%s\n' "$1" | tail -1 | grep -o "[0-9]* $2" | awk '{ s += $1 } END { print s + 0 }'; }
run_pytest() {
  local t0 out rc ok bad sk
  t0=$(date +%s)
  out=$(PYTHONPATH="$PWD/build/python${PYTHONPATH:+:$PYTHONPATH}" "${PYTHON:-/usr/bin/python3}" -m pytest -q -rs \
        -p no:cacheprovider "$1" 2>&1); rc=$?
  ok=$(count "$out" passed); sk=$(count "$out" skipped); bad=$(( $(count "$out" failed) + $(count "$out" error) ))
  if [ "$rc" -ne 0 ] && [ "$bad" -eq 0 ]; then bad=1; fi # pytest itself failed (no tests collected, import error)
  passed=$((passed + ok)); failed=$((failed + bad)); skipped=$((skipped + sk))
  printf '%-28s %3d passed %3d failed %3d skipped  (%ds)\n' "pytest $1" "$ok" "$bad" "$sk" $(( $(date +%s) - t0 ))
  printf '%s\n' "$out" | grep '^SKIPPED' | sed 's/^/  /'
  if [ "$bad" -ne 0 ]; then broken="$broken pytest:$1"; printf '%s\n' "$out" | tail -60; fi
}
for t in "$@"; do
  case "$t" in */python|tests/python) run_pytest "$t"; continue ;; esac
  if [ ! -e "$t" ]; then # named but not built
    echo "$t: no such test program"; failed=$((failed + 1)); broken="$broken $(basename "$t")"; continue
  fi
  [ -f "$t" ] && [ -x "$t" ] || continue
  name=$(basename "$t")
  t0=$(date +%s)
  out=$("$t" 2>&1); rc=$?
  ok=$(printf '%s\n' "$out" | grep -c '^\[       OK \]')
  # each skipped test is listed twice (when it runs and in the summary): count the names once
  skip_names=$(printf '%s\n' "$out" | sed -n 's/^\[  SKIPPED \] \([^ ]*\)$/\1/p' | awk '!seen[$0]++')
  sk=$(printf '%s' "$skip_names" | grep -c .)
  # tests announced; a binary that crashed part-way never prints "N test(s) run"
  total=$(printf '%s\n' "$out" | sed -n 's/^\[==========\] Running \([0-9]*\) test(s)\./\1/p' | awk '{ s += $1 } END { print s + 0 }')
  bad=$((total - ok - sk))
  if [ "$rc" -ne 0 ] && [ "$bad" -le 0 ]; then bad=1; fi   # crashed, sanitizer report or leak at exit
  [ "$bad" -lt 0 ] && bad=0
  passed=$((passed + ok)); failed=$((failed + bad)); skipped=$((skipped + sk))
  printf '%-28s %3d passed %3d failed %3d skipped  (%ds)\n' "$name" "$ok" "$bad" "$sk" $(( $(date +%s) - t0 ))
  for s in $skip_names; do
    why=$(printf '%s\n' "$out" | grep -m1 "^skipped $s: ")
    printf '  %s\n' "${why:-skipped $s}"
  done
  if [ "$bad" -ne 0 ]; then broken="$broken $name"; printf '%s\n' "$out" | tail -40; fi
done
echo "tests took $(( $(date +%s) - start )) s"
[ -n "$broken" ] && echo "failing:$broken"
echo "$passed passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ] && [ "$passed" -gt 0 ]
