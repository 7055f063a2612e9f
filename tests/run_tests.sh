#!/usr/bin/env bash
# Runs cmocka test programs and prints one closing line "N passed, M failed, K skipped": the programs named
# (`make test`, `make check`), or every test_* program in a folder and its module folders (default
# build/san/tests). A folder named tests/python is the Python package's pytest suite, run with $PYTHON (default
# /usr/bin/python3) against the package built in build/python, and counted alike.
# DARTSPP_TEST_JOBS programs (default 2) run at once, the longest first by the seconds each took last time
# (kept in $DARTSPP_TEST_TIMES, default build/.test-times; before the first run, tests/test-times: the
# seconds of a `make test` on 2 cores; a program timed in neither starts first, else the order named); each program's line (passed, failed, skipped, seconds) is printed when it ends, with its skip
# reasons and, when it failed, the end of its output. A skipped test (cmocka's skip(): e.g. the paper's scenes are not beside the checkout) is named with the
# reason it printed and is not a failure. Exit status 0 iff nothing failed and something passed.
set -u
if [ $# -eq 0 ] || { [ $# -eq 1 ] && [ -d "$1" ] && [ "${1%python}" = "$1" ]; }; then
  mapfile -t progs < <(find "${1:-build/san/tests}" -type f -name 'test_*' ! -name '*.*' | sort)
  set -- "${progs[@]}"
fi
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export CMOCKA_MESSAGE_OUTPUT=stdout
# Two programs of two OpenMP threads each share 2 cores: threads that spin at a barrier while the other
# program's threads hold the cores slow both (2026-11-28, idle 2-core machine: test_single_scatter and
# test_photon_single_scatter side by side took 45.7 s with the default policy, 22.6 s passive, 32.7 s one
# after the other). So OpenMP threads wait passively here, unless the caller set the policy.
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
# Programs that must have the machine to themselves (timings of interrupts, the peak memory of a run),
# DARTSPP_TEST_ALONE (the Makefile lists the programs tagged `/* run: alone */`): each starts once no other
# program runs, and none starts while it runs.
alone=" ${DARTSPP_TEST_ALONE:-} "
jobs_max=${DARTSPP_TEST_JOBS:-2}
times=${DARTSPP_TEST_TIMES:-build/.test-times}
known=$(cat "$times" tests/test-times 2>/dev/null) # "seconds path" lines, the newest first
if [ -n "$known" ] && [ $# -gt 1 ]; then # longest first: "seconds position path", sorted, path kept
  mapfile -t order < <(i=0; for t in "$@"; do i=$((i + 1))
                         s=$(printf '%s\n' "$known" | awk -v p="$t" '$2 == p { print $1; f = 1; exit } END { if (!f) print 1e9 }')
                         printf '%s %d %s\n' "$s" "$i" "$t"; done | sort -k1,1gr -k2,2n | cut -d' ' -f3-)
  set -- "${order[@]}"
fi
[ "$jobs_max" -ge 1 ] 2>/dev/null || jobs_max=1
res=$(mktemp -d)
trap 'rm -rf "$res"' EXIT
start=$(date +%s)
# pytest's summary line "== 3 passed, 1 failed, 2 skipped in 4.1s ==": count of one outcome
count() { printf '%s\n' "$1" | tail -1 | grep -o "[0-9]* $2" | awk '{ s += $1 } END { print s + 0 }'; }
# Each job writes its report to $res/i.txt and then "passed failed skipped name" to $res/i.res (renamed into
# place, so a .res file is always whole); the loop below prints and counts them as they appear.
run_pytest() { # i folder
  local t0 out rc ok bad sk
  t0=$(date +%s)
  out=$(PYTHONPATH="$PWD/build/python${PYTHONPATH:+:$PYTHONPATH}" "${PYTHON:-/usr/bin/python3}" -m pytest -q -rs \
        -p no:cacheprovider "$2" 2>&1); rc=$?
  ok=$(count "$out" passed); sk=$(count "$out" skipped); bad=$(( $(count "$out" failed) + $(count "$out" error) ))
  if [ "$rc" -ne 0 ] && [ "$bad" -eq 0 ]; then bad=1; fi # pytest itself failed (no tests collected, import error)
  {
    printf '%-28s %3d passed %3d failed %3d skipped  (%ds)\n' "pytest $2" "$ok" "$bad" "$sk" $(( $(date +%s) - t0 ))
    printf '%s\n' "$out" | grep '^SKIPPED' | sed 's/^/  /'
    if [ "$bad" -ne 0 ]; then printf '%s\n' "$out" | tail -60; fi
  } > "$res/$1.txt"
  echo "$ok $bad $sk $(( $(date +%s) - t0 )) $2 pytest:$2" > "$res/$1.tmp" && mv "$res/$1.tmp" "$res/$1.res"
}
run_program() { # i program
  local t=$2 name t0 out rc ok skip_names sk total bad s why
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
  {
    printf '%-28s %3d passed %3d failed %3d skipped  (%ds)\n' "$name" "$ok" "$bad" "$sk" $(( $(date +%s) - t0 ))
    for s in $skip_names; do
      why=$(printf '%s\n' "$out" | grep -m1 "^skipped $s: ")
      printf '  %s\n' "${why:-skipped $s}"
    done
    if [ "$bad" -ne 0 ]; then printf '%s\n' "$out" | tail -40; fi
  } > "$res/$1.txt"
  echo "$ok $bad $sk $(( $(date +%s) - t0 )) $t $name" > "$res/$1.tmp" && mv "$res/$1.tmp" "$res/$1.res"
}
passed=0; failed=0; skipped=0; broken=""; n=0; shown=0; running=0
declare -A seen=()
report() { # prints and counts every finished job not yet shown
  local f i ok bad sk secs path name
  for f in "$res"/*.res; do
    [ -e "$f" ] || continue
    i=$(basename "$f" .res)
    [ -n "${seen[$i]:-}" ] && continue
    seen[$i]=1; shown=$((shown + 1)); running=$((running - 1))
    read -r ok bad sk secs path name < "$f"
    echo "$secs $path" >> "$res/times"
    cat "$res/$i.txt"
    passed=$((passed + ok)); failed=$((failed + bad)); skipped=$((skipped + sk))
    [ "$bad" -ne 0 ] && broken="$broken $name"
  done
}
for t in "$@"; do
  if [ "${t%/python}" = "$t" ] && [ "$t" != tests/python ]; then
    if [ ! -e "$t" ]; then # named but not built
      echo "$t: no such test program"; failed=$((failed + 1)); broken="$broken $(basename "$t")"; continue
    fi
    [ -f "$t" ] && [ -x "$t" ] || continue
  fi
  report
  limit=$jobs_max
  case "$alone" in *" $t "*) limit=1 ;; esac # waits for every other program to end
  while [ "$running" -ge "$limit" ]; do sleep 0.2; report; done
  n=$((n + 1)); running=$((running + 1))
  case "$t" in */python|tests/python) run_pytest "$n" "$t" & ;; *) run_program "$n" "$t" & ;; esac
  case "$alone" in *" $t "*) wait; report ;; esac # and none starts beside it
done
wait
report
if [ "$shown" -lt "$n" ]; then # a job that wrote no result (its shell was killed)
  echo "$((n - shown)) test program(s) ended without a result"; failed=$((failed + n - shown)); broken="$broken (lost)"
fi
if [ -s "$res/times" ] && mkdir -p "$(dirname "$times")" 2>/dev/null; then # this run's seconds, then the older ones
  { cat "$res/times"; [ -f "$times" ] && cat "$times"; } | awk '!seen[$2]++' > "$times.tmp" && mv "$times.tmp" "$times"
fi
echo "tests took $(( $(date +%s) - start )) s"
[ -n "$broken" ] && echo "failing:$broken"
echo "$passed passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ] && [ "$passed" -gt 0 ]
