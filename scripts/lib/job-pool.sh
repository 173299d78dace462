# Runs commands in the background, at most $HANDTRACK_JOBS (default 2) at once; sourced by the
# benchmark scripts. A command that fails fails the script (set -e) when it is waited for.
#   pool_start            # reads and checks HANDTRACK_JOBS into $jobs
#   pool_run CMD ARGS...  # starts CMD once fewer than $jobs run, its standard output discarded
#   pool_finish           # waits for all, failing on the first that failed
# Each command's pid is kept: a command that ends while the pool never had to wait leaves the
# shell's job table when `jobs` next looks, and only `wait PID` still has its exit status.
pool_start() {
  jobs="${HANDTRACK_JOBS:-2}"
  case "$jobs" in
    '' | *[!0-9]* | 0) echo "$(basename "$0"): HANDTRACK_JOBS must be a positive number, got '$jobs'" >&2; exit 1 ;;
  esac
  pool_pids=()
}
pool_run() {
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n; done
  "$@" >/dev/null &
  pool_pids+=("$!")
}
pool_finish() {
  local pid
  for pid in "${pool_pids[@]}"; do wait "$pid"; done
  pool_pids=()
}
