#!/usr/bin/env bash
# Runs every cmocka test binary in a folder and prints one closing line "N passed, M failed".
set -u
dir=${1:-build/san/tests}
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export CMOCKA_MESSAGE_OUTPUT=stdout
passed=0; failed=0; broken=""
start=$(date +%s)
for t in "$dir"/test_*; do
  [ -x "$t" ] || continue
  name=$(basename "$t")
  t0=$(date +%s)
  out=$("$t" 2>&1); rc=$?
  ok=$(printf '%s\n' "$out" | grep -c '^\[       OK \]')
  run=$(printf '%s\n' "$out" | sed -n 's/^\[==========\] \([0-9]*\) test(s) run\./\1/p' | awk '{ s += $1 } END { print s + 0 }')
  run=${run:-0}
  bad=$((run - ok))
  if [ "$rc" -ne 0 ] && [ "$bad" -eq 0 ]; then bad=1; fi   # crashed or sanitizer abort
  passed=$((passed + ok)); failed=$((failed + bad))
  printf '%-28s %3d passed %3d failed  (%ds)\n' "$name" "$ok" "$bad" $(( $(date +%s) - t0 ))
  if [ "$bad" -ne 0 ]; then broken="$broken $name"; printf '%s\n' "$out" | tail -40; fi
done
echo "tests took $(( $(date +%s) - start )) s"
[ -n "$broken" ] && echo "failing:$broken"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ] && [ "$passed" -gt 0 ]
