# Sourced by the Modbus benchmarks (not a benchmark itself): client and server pinned to one CPU,
# the appliance's scan cycle given all of them back.
#
# PIN_CPU=<taskset cpu list> (default: the last CPU; none: the scheduler places everything) sets
# `pin_cpu` and the command prefix `pin` ("${pin[@]}" cmd ...); `online_cpus` is every CPU.
online_cpus=$(cat /sys/devices/system/cpu/online)  # e.g. 0-1
pin_cpu=${PIN_CPU:-$(($(getconf _NPROCESSORS_ONLN) - 1))}
pin=()
[[ $pin_cpu == none ]] || pin=(taskset -c "$pin_cpu")

# unpin_scan_cycle PID: gives the appliance's SCHED_FIFO thread (the scan cycle) all online CPUs
# back when the process was pinned. The loop thread switches to SCHED_FIFO as it starts, just after
# the Modbus server answers, so it is looked for during at most 2 s.
unpin_scan_cycle() {
  local pid=$1 task
  [[ $pin_cpu != none ]] || return 0
  for _ in $(seq 40); do
    for task in /proc/"$pid"/task/*; do
      if chrt -p "${task##*/}" 2>/dev/null | grep -q SCHED_FIFO; then
        taskset -p -c "$online_cpus" "${task##*/}" >/dev/null
        return 0
      fi
    done
    sleep 0.05
  done
  echo "warning: no SCHED_FIFO thread in the appliance (not root?): its scan cycle stays on CPU $pin_cpu" >&2
}
