#!/bin/sh
# Runs the same models with tricontact and with CalculiX (ccx) and prints results and wall-clock
# times side by side, both codes on two threads. The CalculiX decks come from `tricontact export`
# and `fem-bench --inp` (see the README, "Comparison with CalculiX"). About 8 minutes on two cores.
#
#   apt-get install calculix-ccx      # once (Debian/Ubuntu; CalculiX 2.20 with SPOOLES)
#   sh scripts/compare-calculix.sh    # from the repository root; work files in target/compare-calculix
set -e
command -v ccx >/dev/null 2>&1 || {
  echo "ccx not found: install CalculiX first (Debian/Ubuntu: apt-get install calculix-ccx)" >&2
  exit 1
}
cargo build --release -p tricontact-cli -p tricontact-fem --bins
root=$(pwd)
out=$root/target/compare-calculix
mkdir -p "$out"
T=$root/target/release/tricontact
B=$root/target/release/fem-bench
export OMP_NUM_THREADS=2 CCX_NPROC_EQUATION_SOLVER=2

now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.2f", b - a }'; }
# Last total z-force CalculiX printed for a node set: ccx_force DECK SET
ccx_force() {
  awk -v set="$2" '/total force/ { hit = (index($0, set " and") > 0); next }
    hit && NF == 3 { f = $3; hit = 0 } END { print f }' "$out/$1.dat"
}
# Last value of a column of a history.csv: csv_last FILE COLUMN
csv_last() {
  awk -F, -v col="$2" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == col) c = i; next }
    { v = $c } END { print v }' "$1"
}
run_ccx() { (cd "$out" && ccx -i "$1" > "$1.log" 2>&1) || { echo "ccx failed on $1: see $out/$1.log" >&2; exit 1; }; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", a / b }'; }
# Newton iterations CalculiX reported in its .sta file (column ITRS, every increment).
ccx_iterations() { awk '$1 ~ /^[0-9]+$/ && NF >= 7 { n += $4 } END { print n }' "$out/$1.sta"; }
sci() { awk -v a="$1" 'BEGIN { printf "%.5e", a }'; }
# One table row: name, our time, our iterations, CalculiX's time and iterations, what is compared,
# our value, CalculiX's value.
row() {
  echo "| $1 | $2 s ($3) | $4 s ($5) | $(ratio "$4" "$2") | $(awk -v a="$2" -v i="$3" -v b="$4" -v j="$5" 'BEGIN { printf "%.2f", (b / j) / (a / i) }') | $6 $(sci "$7") vs $(sci "$8") | $(diff_pct "$8" "$7") |"
}
diff_pct() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%+.2f %%", 100 * (a - b) / b }'; }

echo "| model | tricontact: time (Newton iterations) | CalculiX | time ratio CalculiX / tricontact | per iteration | result: tricontact vs CalculiX | difference |"
echo "| --- | --- | --- | --- | --- | --- | --- |"
for level in coarse medium fine; do
  name=hertz-$level
  "$T" export examples/hertz/penalty.toml --mesh examples/hertz/$name.msh -o "$out/$name.inp" > "$out/$name.export"
  t0=$(now); "$T" run examples/hertz/penalty.toml --mesh examples/hertz/$name.msh --output "$out/$name" > "$out/$name.run"; ours=$(since "$t0")
  t0=$(now); run_ccx "$name"; theirs=$(since "$t0")
  f1=$(csv_last "$out/$name/history.csv" top_Rz); f2=$(ccx_force "$name" NB4_TOP)
  it1=$(awk '/^done:/ { print $4 }' "$out/$name.run")
  row "Hertz, penalty, $level mesh" "$ours" "$it1" "$theirs" "$(ccx_iterations "$name")" "force on the top" "$f1" "$f2"
done
for n in 40 80; do
  name=contact-$n
  "$B" --contact $n --inp "$out/$name.inp" > "$out/$name.export"
  "$B" --contact $n > "$out/$name.run"
  ours=$(awk '/penalty:/ { print $2 }' "$out/$name.run")
  f1=$(sed -n 's/.*penalty:.*pressed face \([^;]*\);.*/\1/p' "$out/$name.run")
  t0=$(now); run_ccx "$name"; theirs=$(since "$t0")
  f2=$(ccx_force "$name" NB2_UPPER_ZMAX)
  it1=$(awk '/penalty:/ { print $4 }' "$out/$name.run")
  row "hex8 block on block, penalty (fem-bench --contact $n)" "$ours" "$it1" "$theirs" "$(ccx_iterations "$name")" "force on the pressed face" "$f1" "$f2"
done
for n in 30 40; do
  name=cube-$n
  "$B" $n --inp "$out/$name.inp" > "$out/$name.export"
  t0=$(now); "$B" $n > "$out/$name.run"; ours=$(since "$t0")
  t0=$(now); run_ccx "$name"; theirs=$(since "$t0")
  f2=$(ccx_force "$name" NB1_ZMIN)
  row "hex8 cube $n³, linear elastic (fem-bench $n)" "$ours" 1 "$theirs" "$(ccx_iterations "$name")" "support force" 1 "$f2"
done
