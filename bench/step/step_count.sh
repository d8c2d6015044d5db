#!/bin/sh
# Instructions per controller step of the Zhang & Zeng controller (9 rules,
# n = 6, m = 3), counted by callgrind (deterministic, unlike timings on a
# shared machine), for the generated Rust and the generated C.
#
#   sh bench/step/step_count.sh          # from the repository root
#
# Needs valgrind and a C compiler ($CC, default cc). Rust: the flight crate's
# example `step_count` (1000 steps of `attitude::Controller::step`). C: the
# controller compiled by `tsfc compile --emit c` into a temporary folder,
# built with the flags of tests/tests/c_codegen.rs (-std=c99 -pedantic
# -Wall -Wextra -Werror -O2, plus -ffp-contract=off) around
# bench/step/step_count.c (1000 steps of zhang_multiobjective_step). Each
# count covers the step function and everything it calls. "C f32" is the
# same spec with `precision f32` (its own certified design, single precision
# throughout).
set -eu

CC=${CC:-cc}
TARGET=${CARGO_TARGET_DIR:-target}
SPEC=specs/zhang2013_multiobjective.tsf
STEPS=1000

per_step() {
    # callgrind's "Collected" line / STEPS
    awk -v steps="$STEPS" '/Collected/ { printf "%.1f\n", $4 / steps }'
}

cargo build --quiet --release -p tsfc --bin tsfc
cargo build --quiet --release -p flight-example --example step_count
rust=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null \
    --toggle-collect='*attitude*Controller*step*' \
    "$TARGET/release/examples/step_count" 2>&1 >/dev/null | per_step)

dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

# Instructions per step of the C controller generated from spec $1 into $dir/$2.
c_count() {
    mkdir -p "$dir/$2"
    "$TARGET/release/tsfc" compile "$1" --emit c --out "$dir/$2" >/dev/null 2>&1
    "$CC" -std=c99 -pedantic -Wall -Wextra -Werror -O2 -ffp-contract=off -I"$dir/$2" \
        -o "$dir/$2/step_count" bench/step/step_count.c "$dir/$2/zhang_multiobjective.c" \
        "$dir/$2/tsf_runtime.c" -lm
    valgrind --tool=callgrind --callgrind-out-file=/dev/null \
        --toggle-collect='zhang_multiobjective_step' \
        "$dir/$2/step_count" 2>&1 >/dev/null | per_step
}
c=$(c_count "$SPEC" f64)
sed 's/^precision .*;/precision f32;/' "$SPEC" > "$dir/zhang_f32.tsf"
grep -q '^precision f32;' "$dir/zhang_f32.tsf" || echo 'precision f32;' >> "$dir/zhang_f32.tsf"
c32=$(c_count "$dir/zhang_f32.tsf" f32)

echo "instructions per step (callgrind, $SPEC):"
echo "  Rust    $rust"
echo "  C       $c"
echo "  C f32   $c32"
