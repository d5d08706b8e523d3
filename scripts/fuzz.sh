#!/usr/bin/env bash
# SPDX-License-Identifier: LGPL-2.1-or-later
# Fuzzes the readers and the core, time-boxed. One target at a time, one process each.
#
#   scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET ...]
#
# Targets: read_off read_tetgen surface_check tetrahedralize (libFuzzer, built with clang and
# ASan+UBSan into build-fuzz/) and python_readers (scripts/fuzz_python_readers.py: random mutations
# of seed files through every Python reader; only typed errors may come out). Default: 60 s each.
# Working corpora grow in build-fuzz/corpus/<target>/; a crash leaves its input in
# build-fuzz/findings/<target>/ and makes the script exit 1. Pin every finding: copy it into
# cpp_module/fuzz/regressions/<target>/ (replayed by CTest) or, for the Python readers, into
# tests/data/fuzz/ (replayed by tests/test_bad_input.py), then fix the cause.
set -uo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=${FEMBSPTET_FUZZ_BUILD_DIR:-$ROOT/build-fuzz}
SECONDS_PER_TARGET=${1:-60}
shift || true
TARGETS=("$@")
((${#TARGETS[@]})) || TARGETS=(read_off read_tetgen surface_check tetrahedralize python_readers)
CXX_FUZZ=${CXX_FUZZ:-$(command -v clang++-14 || command -v clang++)}

needs_cpp=0
for t in "${TARGETS[@]}"; do [ "$t" != python_readers ] && needs_cpp=1; done
if ((needs_cpp)); then
  [ -n "$CXX_FUZZ" ] || { echo "fuzz: clang++ is missing (apt-get install clang-14)" >&2; exit 1; }
  if [ ! -f "$BUILD/CMakeCache.txt" ]; then
    cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER="$CXX_FUZZ" \
      -DFEMBSPTET_FUZZ=ON -DFEMBSPTET_BUILD_TESTS=OFF -DFEMBSPTET_BUILD_PYTHON=OFF >/dev/null || exit 1
  fi
  cmake --build "$BUILD" --parallel "${FEMBSPTET_JOBS:-2}" || exit 1
fi

status=0
for t in "${TARGETS[@]}"; do
  echo "== fuzz $t: ${SECONDS_PER_TARGET} s =="
  if [ "$t" = python_readers ]; then
    /usr/bin/python3 "$ROOT/scripts/fuzz_python_readers.py" --seconds "$SECONDS_PER_TARGET" \
      --findings "$BUILD/findings/python_readers" || status=1
    continue
  fi
  corpus="$BUILD/corpus/$t" findings="$BUILD/findings/$t"
  mkdir -p "$corpus" "$findings"
  seeds=("$ROOT/cpp_module/fuzz/regressions/$t")
  [ "$t" = read_off ] && seeds+=("$ROOT/tests/data/paper")
  log="$BUILD/fuzz-$t.log"
  "$BUILD/cpp_module/fuzz/fuzz_$t" "$corpus" "${seeds[@]}" -max_total_time="$SECONDS_PER_TARGET" \
    -timeout=20 -rss_limit_mb=2048 -max_len=4096 -print_final_stats=1 -artifact_prefix="$findings/" \
    >"$log" 2>&1
  rc=$?
  grep -E "^(Done|stat::number_of_executed_units|stat::peak_rss_mb)|ERROR|SUMMARY" "$log"
  if [ $rc -ne 0 ]; then
    echo "fuzz $t: FAILED (exit $rc); see $log and $findings/" >&2
    status=1
  fi
done
exit $status
