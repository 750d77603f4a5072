#!/bin/sh
# Runs every example of VERIFICATION.md and writes its results (tables, plots) under
# examples/*/results/. About 1¼ minutes on two cores, most of it the three fine Hertz runs.
#   sh scripts/verify.sh
set -e
cargo build --release -p tricontact-cli
run() { ./target/release/tricontact run "$@"; }
for m in multiplier penalty augmented; do
  for level in coarse medium fine; do
    run examples/hertz/$m.toml --mesh examples/hertz/hertz-$level.msh \
      --output examples/hertz/results/$m-$level
  done
done
for m in multiplier augmented penalty two-pass; do
  for mesh in matching-hex nonmatching-hex nonmatching-tet; do
    run examples/patch/$m.toml --mesh examples/patch/$mesh.msh \
      --output examples/patch/results/$m-$mesh
  done
done
run examples/sliding/model.toml
run examples/self-contact/model.toml
run examples/self-contact/two-groups.toml
for level in coarse medium fine; do
  ./target/release/tricontact plot examples/hertz/results/multiplier-$level \
    examples/hertz/results/penalty-$level examples/hertz/results/augmented-$level \
    --increment 1:8 --output examples/hertz/results/newton-$level.png
done
