#!/bin/sh
# The default penalty measured against two alternatives (README, "The default penalty"): each model
# of examples/penalty-study/ and examples/contact-block/ is run with the default `10 E h`
# (E = √(E_m E_s), the geometric mean of the master's and the slave's moduli) and with the penalty
# given as `10 E h` of the master's modulus (the default until 2026-12-05) and of the smaller
# modulus: the values written below, with `h` each pair's mean master facet edge as
# `tricontact check MODEL` prints it (to four digits). Prints one
# line per run: its last line (increments, iterations, cutbacks, or the error), and the normal
# force of the model's last pair at its end. About 12 minutes on two
# cores (the hump runs take most of it).
#   sh scripts/default-penalty.sh
set -e
cargo build --release -p tricontact-cli
bin=./target/release/tricontact
out=$(mktemp -d)
cleanup() { rm -rf "$out" examples/*/study*.tmp examples/contact-block/study-*.toml; }
trap cleanup EXIT
trap 'cleanup; exit 1' INT TERM

# run NAME MODEL PENALTY... : the model with `penalty = P` after the `method` line of its k-th
# [[contact]] for the k-th P ("default": none).
run() {
  name=$1 model=$2
  shift 2
  dir=$(dirname "$model")
  awk -v list="$*" 'BEGIN { n = split(list, p, " ") }
    { print }
    /^method = / { k++; if (k <= n && p[k] != "default") print "penalty = " p[k] }' \
    "$model" > "$dir/study.tmp"
  tail=$($bin run "$dir/study.tmp" --output "$out/$name" 2>&1 | tail -n 2)
  rm -f "$dir/study.tmp"
  force=$(echo "$tail" | sed -n 's/.*normal force \([^,]*\),.*/\1/p' | tail -n 1)
  last=$(echo "$tail" | tail -n 1 | sed 's/; results in.*//' | cut -c1-160)
  echo "$name: $last${force:+; normal force $force}"
}

s=examples/penalty-study
c=examples/contact-block/model.toml
for m in multiplier penalty augmented; do
  sed "s/method = \"multiplier\"/method = \"$m\"/" $c > examples/contact-block/study-$m.toml
  run "contact-block $m, default" examples/contact-block/study-$m.toml default
  run "contact-block $m, master's E" examples/contact-block/study-$m.toml 2845.2
  run "contact-block $m, smaller E" examples/contact-block/study-$m.toml 284.52
  rm -f examples/contact-block/study-$m.toml
done
for m in penalty augmented; do
  sed -e "s/method = \"multiplier\"/method = \"$m\"/" -e 's/z = -0.05/z = -0.15/' \
    -e 's/^nlgeom = true/nlgeom = true\nline_search = false/' $c > examples/contact-block/study-30-$m.toml
  run "contact-block 30 % $m, no line search, default" examples/contact-block/study-30-$m.toml default
  run "contact-block 30 % $m, no line search, master's E" examples/contact-block/study-30-$m.toml 2845.2
  run "contact-block 30 % $m, no line search, smaller E" examples/contact-block/study-30-$m.toml 284.52
  rm -f examples/contact-block/study-30-$m.toml
done
for m in multiplier penalty augmented; do
  run "hump $m, default" $s/hump-$m.toml default
  run "hump $m, master's E" $s/hump-$m.toml 842.4
  run "hump $m, smaller E" $s/hump-$m.toml 8.424
done
run "stack, default" $s/stack-augmented.toml default default
run "stack, master's E" $s/stack-augmented.toml 1024 11380
run "stack, smaller E" $s/stack-augmented.toml 102.4 1138
run "slide-off two-pass, default" $s/slide-off-two-pass.toml default
run "slide-off two-pass, master's E" $s/slide-off-two-pass.toml 1423
run "slide-off two-pass, smaller E" $s/slide-off-two-pass.toml 142.3
