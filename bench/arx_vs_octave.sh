#!/usr/bin/env bash
# Peer check of our ARX least squares (src/ident/arx_estimator.*) against GNU Octave's control
# package `arx` on the same 100,000 samples: coefficients and time. A benchmark, not a ctest test.
#
#   bench/arx_vs_octave.sh [BUILD_DIR=build/release] [SAMPLES=100000] [REPEATS=20]
#
# Installs octave and octave-control (Debian) if missing (scripts/install-deps.sh bench). Both sides are timed from data in memory
# to coefficients (regression matrix, QR, solve), repeated, best and median reported; Octave's
# start-up, `pkg load` and file reading are outside its tic/toc.
#
# Conventions, aligned explicitly: MATLAB and we write B(q) = b_1 q^-nk + ... + b_nb q^-(nk+nb-1)
# with nk >= 1 for a strictly proper model. octave-control 3.4's arx regresses y(t) on
# u(t-1-nk) ... u(t-nb-nk) (its "nk" shifts the data by nk on top of the one-sample delay it always
# has, and it pads B with 1+nk leading zeros), so our nk = 1 is its nk = 0 (the default). Both start
# the regression at the same row, t = max(na, nb) + 1 (1-based), so they solve the same problem.
set -euo pipefail

build=${1:-build/release}
samples=${2:-100000}
repeats=${3:-20}
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"

scripts/install-deps.sh bench  # octave, octave-control

cmake --build "$build" --target arx_bench >/dev/null
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

bench_bin="$build/bench/arx_bench"
"$bench_bin" "$work/data.csv" "$samples" "$repeats" > "$work/ours.txt"

cat > "$work/octave_arx.m" <<EOF
pkg load control
d = csvread("$work/data.csv");
dat = iddata(d(:, 2), d(:, 1), 0.005);
t = zeros($repeats, 1);
for r = 1:$repeats
  tic; sys = arx(dat, "na", 3, "nb", 3); t(r) = toc;   % octave nk = 0 == our nk = 1 (see above)
end
[num, den] = filtdata(sys);
A = den{1, 1}(:).';  B = num{1, 1}(:).';
printf("octave_ms_min %.4f\noctave_ms_median %.4f\n", 1000 * min(t), 1000 * median(t));
printf("a"); printf(" %.17g", A(2:4)); printf("\n");
printf("b"); printf(" %.17g", B(find(B != 0, 1):end)); printf("\n");
printf("octave_B_padded"); printf(" %.17g", B); printf("\n");
EOF
octave-cli -q "$work/octave_arx.m" > "$work/octave.txt" 2>/dev/null

awk '
  FNR == NR { if ($1 == "a" || $1 == "b") for (i = 2; i <= NF; ++i) ours[$1, i] = $i; else v[$1] = $2; next }
  { if ($1 == "a" || $1 == "b") for (i = 2; i <= NF; ++i) theirs[$1, i] = $i; else v[$1] = $2 }
  END {
    maxd = 0
    for (k in ours) { d = ours[k] - theirs[k]; if (d < 0) d = -d; if (d > maxd) maxd = d }
    printf "samples: %d (%d regression rows), ARX na=3 nb=3 nk=1 (the paper eq 9 + white equation noise)\n", v["samples"], v["rows"]
    printf "ours:   a = [%s %s %s], b = [%s %s %s]\n", ours["a",2], ours["a",3], ours["a",4], ours["b",2], ours["b",3], ours["b",4]
    printf "octave: a = [%s %s %s], b = [%s %s %s]\n", theirs["a",2], theirs["a",3], theirs["a",4], theirs["b",2], theirs["b",3], theirs["b",4]
    printf "max |coefficient difference| = %.3g\n", maxd
    printf "time (best / median of repeats): ours %.3f / %.3f ms, octave %.3f / %.3f ms\n", v["ours_ms_min"], v["ours_ms_median"], v["octave_ms_min"], v["octave_ms_median"]
    printf "speed ratio octave / ours: %.1fx (best), %.1fx (median)\n", v["octave_ms_min"] / v["ours_ms_min"], v["octave_ms_median"] / v["ours_ms_median"]
  }' "$work/ours.txt" "$work/octave.txt"
