# Sourced by the planner suites (explore-suite, taskflow-suite, tensorfield-suite): with
# VOXPLAN_SUITE_MPI=N, the suite queues each run's command in OUT/farm_tasks.txt instead of
# running it, then runs the queue as a task farm over N MPI ranks (`mpirun -n N voxplan farm`,
# distributed/task_farm.h), which deals the runs to the ranks as they become free. Each run
# writes only its own folder and log, so the outputs are the serial suite's; the summary that
# follows reads them the same way. Unset or 0: the suite runs its runs itself, one by one.
# Needs the variables `out` and `voxplan` of the suite.
farm_ranks=${VOXPLAN_SUITE_MPI:-0}
[[ $farm_ranks =~ ^[0-9]+$ ]] || { echo "error: VOXPLAN_SUITE_MPI must be a rank count, got '$farm_ranks'" >&2; exit 2; }

farm_enabled() { ((farm_ranks > 0)); }

farm_init() {  # an empty queue
  farm_enabled || return 0
  command -v mpirun >/dev/null || { echo "error: VOXPLAN_SUITE_MPI needs mpirun (scripts/setup-deps installs OpenMPI)" >&2; exit 2; }
  : >"$out/farm_tasks.txt"
}

farm_queue() {  # LOG CMD...: one task, CMD with its output to LOG
  local log=$1
  shift
  { printf '%q ' "$@"; printf '>%q 2>&1\n' "$log"; } >>"$out/farm_tasks.txt"
}

farm_run() {  # the queue over farm_ranks ranks; a failed run shows in farm.json and its log
  farm_enabled || return 0
  local opts=(--bind-to none)  # each run may use threads of its own
  [[ $(id -u) -eq 0 ]] && opts+=(--allow-run-as-root)
  ((farm_ranks > $(nproc))) && opts+=(--oversubscribe)
  echo "farm: $(grep -c . "$out/farm_tasks.txt") runs over $farm_ranks MPI ranks"
  mpirun "${opts[@]}" -n "$farm_ranks" "$voxplan" farm "$out/farm_tasks.txt" \
    --stats "$out/farm.json" || echo "farm: some runs failed (see $out/farm.json and their logs)" >&2
}
