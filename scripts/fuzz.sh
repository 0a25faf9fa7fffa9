#!/usr/bin/env bash
# Builds the libFuzzer targets (preset fuzz: clang 14, ASan + UBSan, build/fuzz) and runs
# each for N seconds, one after another, from its seed corpus (fuzz/corpus/<target>, read only)
# plus what earlier runs found (build/fuzz/corpus/<target>), with its dictionary. Prints
# executions, exec/s and new corpus entries per target; a crash, leak, timeout or sanitizer
# report fails the script and leaves the input in build/fuzz/artifacts/ to replay:
#   build/fuzz/fuzz/<target> build/fuzz/artifacts/<target>-crash-...
#
#   scripts/fuzz.sh [seconds per target, default 10] [target ...]
#   scripts/fuzz.sh --build-only [target ...]
set -euo pipefail
cd "$(dirname "$0")/.."
build_only=no
seconds=10
if [ "${1:-}" = --build-only ]; then  # .ci/run compiles ahead while the release suite runs
  build_only=yes
  shift
elif [ $# -gt 0 ]; then
  seconds=$1
  shift
fi
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(fuzz_modbus_request fuzz_register_map fuzz_run_file fuzz_config fuzz_http_params fuzz_tls_handshake)

scripts/install-deps.sh
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz --target "${targets[@]}"
[ $build_only = yes ] && exit 0

declare -A max_len=([fuzz_modbus_request]=1024)  # a few ADUs of at most 260 bytes
mkdir -p build/fuzz/artifacts
failed=0
summary=()
for t in "${targets[@]}"; do
  work=build/fuzz/corpus/$t
  mkdir -p "$work"
  dict=()
  [ -f fuzz/dict/$t.dict ] && dict=(-dict=fuzz/dict/$t.dict)
  log=build/fuzz/$t.log
  echo "fuzz: $t for ${seconds} s"
  rc=0
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ASAN_OPTIONS=detect_leaks=1 \
    build/fuzz/fuzz/$t -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len="${max_len[$t]:-8192}" \
    -print_final_stats=1 -artifact_prefix="build/fuzz/artifacts/$t-" "${dict[@]}" "$work" "fuzz/corpus/$t" \
    >"$log" 2>&1 || rc=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  corpus=$(ls "$work" | wc -l)
  if [ $rc -ne 0 ]; then
    failed=1
    echo "fuzz: $t FAILED (exit $rc); the end of $log:" >&2
    tail -40 "$log" >&2
    summary+=("$(printf '%-22s %12s %8s %8s  CRASH (exit %d): %s' "$t" "${execs:-?}" "${rate:-?}" "$corpus" "$rc" "$(ls -t build/fuzz/artifacts/$t-* 2>/dev/null | head -1)")")
  else
    summary+=("$(printf '%-22s %12s %8s %8s  0 crashes' "$t" "$execs" "$rate" "$corpus")")
  fi
done
printf '%-22s %12s %8s %8s  %s\n' target executions exec/s corpus result
printf '%s\n' "${summary[@]}"
exit $failed
