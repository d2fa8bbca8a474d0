#!/usr/bin/env bash
# The path model's stable speed figure: the instructions a fixed small render executes, counted by
# valgrind's callgrind. Unlike a time, the count is the same on every run of the same binary and
# input, whatever else the machine is doing, so a change to a hot loop can be judged before its
# time is measured against Mitsuba (cargo bench -p raytracer --bench pbr).
#
# Usage: tools/callgrind-path.sh [SCENE] [extra render options...]
#   default: scenes/cornell-box.txt --model path --size 64x64 --spp 4, one thread.
# Prints the total instruction count (Ir) and the ten functions with the most, and leaves the full
# profile in target/callgrind/ for callgrind_annotate or kcachegrind.
# Needs valgrind (apt-get install valgrind).
set -euo pipefail
cd "$(dirname "$0")/.."
scene="${1:-scenes/cornell-box.txt}"
shift || true
command -v valgrind >/dev/null || { echo "valgrind is not installed (apt-get install valgrind)" >&2; exit 1; }
cargo build --release -q -p rayterra
mkdir -p target/callgrind
out="target/callgrind/path.$(date +%Y%m%d-%H%M%S).out"
# One thread: the count of a multi-threaded run depends on how work is stolen.
valgrind --tool=callgrind --callgrind-out-file="$out" \
    target/release/rayterra render "$scene" --model path --size 64x64 --spp 4 --threads 1 \
    -o target/callgrind/path.exr "$@" >/dev/null 2>target/callgrind/valgrind.log
annotated=$(callgrind_annotate "$out")
total=$(awk '/PROGRAM TOTALS/ && !done { gsub(",", "", $1); print $1; done = 1 }' <<<"$annotated")
echo "instructions: $total  ($scene, path model, 64x64, 4 spp, 1 thread; profile: $out)"
awk '/file:function/ { on = 1; next } on && NF && !/^-+$/ && n < 10 { print; n++ }' <<<"$annotated"
