#!/usr/bin/env bash
# Fuzz Clip::parse + every way of playing (decoder-nostd/fuzz). Needs a
# nightly toolchain and cargo-fuzz (`cargo install cargo-fuzz`). The corpus is
# seeded with real clips: the shipped demo and, when present, clips encoded
# from the CMU corpus, so the fuzzer starts from valid files.
#   bash scripts/fuzz.sh [SECONDS]      (default 120)
set -euo pipefail
cd "$(dirname "$0")/.."
secs="${1:-120}"
seeds=decoder-nostd/fuzz/corpus/parse_and_play
mkdir -p "$seeds"
cp firmware-example/clips/demo.mcb "$seeds/demo.mcb"
cargo build --release -q -p mocap-cli
corpus="${MOCAP_CORPUS:-../shared/data}"
for f in "$corpus"/cmu/35_17.bvh "$corpus"/cmu/09_01.bvh; do
    [ -f "$f" ] || continue
    for k in 0 8; do
        target/release/mocap encode "$f" -o "$seeds/$(basename "$f" .bvh)_k$k.mcb" --key-interval "$k" >/dev/null 2>&1
    done
    # pca-spline: segments, blends, patches.
    target/release/mocap encode "$f" -o "$seeds/$(basename "$f" .bvh)_pca.mcb" --codec pca-spline \
        --max-error 50mm >/dev/null 2>&1
done
target/release/mocap encode assets/animatronic_demo.bvh -o "$seeds/demo_pca.mcb" --codec pca-spline >/dev/null 2>&1
# predictive: blocks, range-coded residuals (short blocks: many restarts).
target/release/mocap encode assets/animatronic_demo.bvh -o "$seeds/demo_pred.mcb" --codec predictive \
    --max-error 0.5deg --key-interval 16 >/dev/null 2>&1
# A servo clip (rig table).
target/release/mocap encode assets/animatronic_demo.bvh --rig assets/rigs/animatronic_demo.toml \
    -o "$seeds/demo_servo.mcb" --codec pca-spline --max-error 1deg >/dev/null 2>&1
target/release/mocap encode assets/animatronic_demo.bvh --rig assets/rigs/animatronic_demo.toml \
    -o "$seeds/demo_servo_pred.mcb" --codec predictive --max-error 0.5deg >/dev/null 2>&1
cd decoder-nostd/fuzz
cargo +nightly fuzz run parse_and_play -- -max_total_time="$secs" -max_len=65536
