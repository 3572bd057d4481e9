#!/usr/bin/env bash
# The MPI pack build side by side with one process: parallel efficiency from
# 1 to 2 ranks, split by observers (the default) and by rows, each rank's time
# split (hull, scatter, the other ranks' sums, terrain force field, write,
# waiting for the others) and the bytes exchanged, medians of N runs.
#
#   tools/bench/mpi_build_bench.sh [BUILD_DIR] [N] [-- visvol build options...]
#
# Default: the Taunus 512 x 512 DEM at 90 m, 128 levels, cube range 64, three
# levels of detail (the fieldbench's case as a whole pack), 3 runs. One worker
# thread a rank, so 1 and 2 ranks compare the same cores' work; `visvol build
# --threads 2` is measured beside them as the single-process reference.
# Needs a build with -DVISVOL_MPI=ON (tools/test.sh makes one in build/).
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
runs=${2:-3}
shift $(($# < 2 ? $# : 2))
[[ ${1:-} == -- ]] && shift
options=("$@")
((${#options[@]})) || options=(tests/data/taunus_utm32n_90m_512.tif --levels 128 --range 64 --lod 3)
visvol=$build/tools/visvol/visvol
mpi=$build/tools/build-mpi/visvol-build-mpi
[[ -x $mpi ]] || { echo "mpi_build_bench: $mpi not built (cmake -DVISVOL_MPI=ON)" >&2; exit 2; }
mpirun=(mpirun --oversubscribe --allow-run-as-root --mca btl self,vader --mca oob_tcp_if_include lo)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

seconds() {  # seconds COMMAND...: wall time of COMMAND, its output in $work/last
  local t0 t1
  t0=$(date +%s.%N)
  "$@" >"$work/last" 2>&1 || { cat "$work/last" >&2; return 1; }
  t1=$(date +%s.%N)
  awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }'
}
median() { printf '%s\n' "$@" | sort -g | awk '{v[NR]=$1} END {print (NR % 2) ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2}'; }

one_thread=() two_threads=() one_rank=() two_ranks=() two_ranks_rows=()
for ((i = 1; i <= runs; ++i)); do
  echo "run $i of $runs" >&2
  two_threads+=("$(seconds "$visvol" build "${options[@]}" --threads 2 -o "$work/ref.vvp")")
  one_thread+=("$(seconds "$visvol" build "${options[@]}" --threads 1 -o "$work/ref.vvp")")
  one_rank+=("$(seconds "${mpirun[@]}" -np 1 "$mpi" "${options[@]}" --threads 1 -o "$work/one.vvp")")
  sed -n '/^rank /,/^exchanged/p' "$work/last" | sed "s/^/run $i, 1 rank:  /" >>"$work/ranks.txt"
  two_ranks+=("$(seconds "${mpirun[@]}" -np 2 "$mpi" "${options[@]}" --threads 1 -o "$work/two.vvp")")
  sed -n '/^rank /,/^exchanged/p' "$work/last" | sed "s/^/run $i, 2 ranks: /" >>"$work/ranks.txt"
  two_ranks_rows+=("$(seconds "${mpirun[@]}" -np 2 "$mpi" "${options[@]}" --threads 1 --split rows -o "$work/two.vvp")")
  sed -n '/^rank /,/^exchanged/p' "$work/last" | sed "s/^/run $i, 2 ranks, --split rows: /" >>"$work/ranks.txt"
done
t1=$(median "${one_rank[@]}")
t2=$(median "${two_ranks[@]}")
t2_rows=$(median "${two_ranks_rows[@]}")
echo "== visvol build ${options[*]} ($(nproc) cores, median of $runs)"
printf '   %-40s %7.2f s\n' "visvol build, 1 thread" "$(median "${one_thread[@]}")"
printf '   %-40s %7.2f s\n' "visvol build, 2 threads" "$(median "${two_threads[@]}")"
printf '   %-40s %7.2f s\n' "visvol-build-mpi, 1 rank x 1 thread" "$t1"
printf '   %-40s %7.2f s\n' "visvol-build-mpi, 2 ranks x 1 thread" "$t2"
printf '   %-40s %7.2f s\n' "the same, --split rows" "$t2_rows"
efficiency() { awk -v a="$1" -v b="$2" 'BEGIN { print a / (2 * b) }'; }
printf '   %-40s %7.2f (--split rows: %.2f)\n' "parallel efficiency 1 -> 2 ranks" "$(efficiency "$t1" "$t2")" \
  "$(efficiency "$t1" "$t2_rows")"
echo "== every run's rank lines (hull, scatter, terrain force field: the model's --measured from the 1-rank ones)"
cat "$work/ranks.txt"
