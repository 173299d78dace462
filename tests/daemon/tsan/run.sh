#!/usr/bin/env bash
# The pipeline tests under ThreadSanitizer, run by ctest (tests/daemon/CMakeLists.txt): a second,
# small build of the same project (HANDTRACK_SANITIZE=thread) inside the main build tree, of the
# one target daemon_pipeline_test and what it links.
#   run.sh build SRC DIR    configure (once) and build
#   run.sh test DIR         run the pipeline tests; any report fails (halt_on_error)
set -euo pipefail
job="$1"
case "$job" in
  build)
    src="$2" dir="$3"
    if [ ! -f "$dir/CMakeCache.txt" ]; then
      # -Werror off: gcc warns that TSan does not model atomic_thread_fence (ipc's seqlock); the
      # plain build keeps the project warning-clean.
      # A unity build with line tables only (-g1, enough for TSan's stacks): 80 s instead of 180 s
      # on the project's 2-core machine.
      cmake -S "$src" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DHANDTRACK_SANITIZE=thread \
        -DHANDTRACK_WERROR=OFF -DCMAKE_UNITY_BUILD=ON "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" >/dev/null
    fi
    cmake --build "$dir" -j"${HANDTRACK_JOBS:-2}" --target daemon_pipeline_test ;;
  test)
    dir="$2"
    here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
    TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$here/suppressions.txt" \
      "$dir/tests/daemon/daemon_pipeline_test" ;;
  *) echo "run.sh: unknown job $job" >&2; exit 2 ;;
esac
