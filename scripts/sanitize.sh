#!/usr/bin/env bash
# SPDX-License-Identifier: LGPL-2.1-or-later
# The C++ suite under AddressSanitizer + UndefinedBehaviorSanitizer, in its own build
# directory (build-sanitize/; the Python extension is not built there, so the one in the source
# tree stays uninstrumented). Runs the whole C++ suite: the unit tests (label `unit`: GoogleTest,
# the fuzz-finding replays) and every corpus model (label `corpus`); any sanitizer report fails
# the test that caused it.
#
#   scripts/sanitize.sh            # about 25 minutes on 2 cores (fandisk and adis16480 the longest)
set -uo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=${FEMBSPTET_SANITIZE_BUILD_DIR:-$ROOT/build-sanitize}
"$ROOT/scripts/setup.sh" >/dev/null || exit 1   # packages (the normal build is not needed here)
# -O2: the sanitizers see the same code paths; -O1 made the large corpus models (adis16480,
# fandisk) take over 15 minutes each here.
cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O2 -g" \
  -DFEMBSPTET_SANITIZE=ON -DFEMBSPTET_BUILD_PYTHON=OFF -DFEMBSPTET_CORPUS_TIMEOUT=3600 >/dev/null || exit 1
cmake --build "$BUILD" --parallel "${FEMBSPTET_JOBS:-2}" || exit 1
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir "$BUILD" --output-on-failure --timeout 900 -L unit || status=1
ctest --test-dir "$BUILD" --output-on-failure -j "${FEMBSPTET_JOBS:-2}" -L corpus || status=1
exit ${status:-0}
