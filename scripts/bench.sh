#!/usr/bin/env bash
# Every figure of BENCHMARKS.md in one run:
#  1. `mocap bench` over the corpus folders, codecs index, pca-spline and auto, at 1°, 0.25°,
#     20 mm and 50 mm with ARMS ≤ 10 mm (ratios, errors, encode times), and pca-spline encode
#     time against clip length;
#  2. decode cost in QEMU with -icount shift=0 on Cortex-M0/M3/M4F for one CMU clip;
#  3. firmware and decoder sizes, decoder state size;
#  4. shows (BENCHMARKS.md §6): the show files' bytes against their clips as single files
#     (`mocap show build`), the index table pools of the iclone show and what sharing them could
#     save (encoder/examples/show_pools.rs), and the blend safety figures of every transition of
#     the CMU servo and demo shows (tests/tests/show_blend_safety.rs).
#  5. against what users pick instead (BENCHMARKS.md "Against what users pick instead
#     (issue 15)"): our codecs beside raw 16-bit frames, quantisation + zstd / xz and
#     keyframe-linear reduction, per-folder totals, on cmu, cmu-long, iclone-cmu and the
#     asf-amc .amc files at 1°, 20 mm and 50 mm + ARMS 10 mm, and the C3D marker files at
#     5 mm, 20 mm and 50 mm + ARMS 10 mm (the picture: target/bench/baselines.png).
#  6. the readers' throughput and a folder of 500 files (encoder/examples/read_folder.rs).
#   bash scripts/bench.sh [CLIP.bvh]   (default: $MOCAP_CORPUS/cmu/35_01.bvh)
#   bash scripts/bench.sh --baselines  (part 5 alone: no QEMU, no cross toolchain)
#   bash scripts/bench.sh --decode [CLIP.bvh]  (part 2 alone: the decode tables in QEMU)
#   bash scripts/bench.sh --baselines --write  (the same, and its tables and picture written
#     into BENCHMARKS.md §1d between its `<!-- bench:... -->` markers and docs/bench_baselines.png)
#   Failing steps print why (their output is in target/bench/steps.log).
set -euo pipefail
# shellcheck source=scripts/toolchain.sh
source "$(dirname "${BASH_SOURCE[0]}")/toolchain.sh"
cd "$MOCAP_REPO_ROOT"
corpus="${MOCAP_CORPUS:-../shared/data}"

# Part 5: the tables of BENCHMARKS.md "Against what users pick instead (issue 15)".
baselines_part() {
    local mocap=$1 out=$2
    local codecs=(--codec index --codec pca-spline --codec predictive --codec auto --baselines)
    echo "## Against what users pick instead (issue 15)"
    echo
    echo "mocap bench $corpus/cmu $corpus/cmu-long $corpus/iclone-cmu $corpus/asf-amc/*.amc ${codecs[*]} --max-error 1deg --max-error 20mm --max-error 50mm+arms:10mm --summary"
    echo
    /usr/bin/time -f "wall time: %e s" -o "$out/baselines.time" \
        "$mocap" bench "$corpus/cmu" "$corpus/cmu-long" "$corpus/iclone-cmu" "$corpus"/asf-amc/*.amc \
        "${codecs[@]}" --max-error 1deg --max-error 20mm --max-error 50mm+arms:10mm --summary \
        --json "$out/baselines.json" --plot "$out/baselines.png" 2>"$out/baselines.log" |
        tee "$out/baselines.md"
    cat "$out/baselines.time"
    echo
    echo "mocap bench $corpus/c3d ${codecs[*]} --max-error 5mm --max-error 20mm --max-error 50mm+arms:10mm --summary"
    echo
    /usr/bin/time -f "wall time: %e s" -o "$out/baselines-c3d.time" \
        "$mocap" bench "$corpus/c3d" "${codecs[@]}" --max-error 5mm --max-error 20mm \
        --max-error 50mm+arms:10mm --summary \
        --json "$out/baselines-c3d.json" 2>"$out/baselines-c3d.log" | tee "$out/baselines-c3d.md"
    cat "$out/baselines-c3d.time"
    echo
}

# shellcheck source=scripts/bench_splice.sh
source scripts/bench_splice.sh

if [ "${1:-}" = --baselines ]; then
    cargo build --release -q -p mocap-cli
    mkdir -p target/bench
    baselines_part "${CARGO_TARGET_DIR:-target}/release/mocap" target/bench
    if [ "${2:-}" = --write ]; then
        splice_benchmarks baselines target/bench/baselines.md
        splice_benchmarks baselines-c3d target/bench/baselines-c3d.md
        cp target/bench/baselines.png docs/bench_baselines.png
        echo "wrote BENCHMARKS.md §1d's tables and docs/bench_baselines.png"
    fi
    exit 0
fi

mocap_toolchain_setup >&2
cargo build --release -q -p mocap-cli
cargo build --release -q -p mocap-encoder --example show_pools
mocap="${CARGO_TARGET_DIR:-target}/release/mocap"
show_pools="${CARGO_TARGET_DIR:-target}/release/examples/show_pools"
out=target/bench
mkdir -p "$out"
log="$out/steps.log"
: >"$log"
mocap_explain_failure bench.sh "$log"

# Part 2: decode cost in QEMU (-icount shift=0) of one clip on every board, then the 35_01
# pose tables of every codec (frames and 50 Hz sample_at, the cost model's prediction, the
# playback stack and the state) and the firmware's flash.
decode_part() {
    local clip_src="${1:-$corpus/cmu/35_01.bvh}" channels pca_src board core pc line per worst stack pstack predicted state name us mode extra
    mocap_logged "$log" "$mocap" encode "$clip_src" -o "$out/clip.mcb" --max-error 1deg
    channels=$("$mocap" info "$out/clip.mcb" | sed -n 's/.* × \([0-9]*\) channels.*/\1/p')
    echo "## Decode cost in QEMU (-icount shift=0), $(basename "$clip_src") at 1°, $channels channels"
    echo
    echo "| core | board | instructions/frame | instructions/channel/frame | Clip::parse (CRC incl.) | Player::new | stack used B | Player<320> state B |"
    echo "|---|---|---|---|---|---|---|---|"
    for board in $(mocap_boards); do
        core=$(mocap_board_core "$board")
        bash scripts/firmware.sh run --board "$board" --clip "$out/clip.mcb" --icount 2>>"$log" >"$out/uart-$board.txt" \
            || { echo "bench.sh: firmware run on $board failed; last lines of $log:" >&2; tail -n 25 "$log" >&2; exit 1; }
        get() { sed -n "s/.*$1=\([0-9]*\).*/\1/p" "$out/uart-$board.txt" | head -1; }
        pc=$(sed -n 's/^# decode_instructions_total=.* per_channel_x100=\([0-9]*\).*/\1/p' "$out/uart-$board.txt")
        echo "| $core | $board | $(sed -n 's/^# decode_instructions_total=.* per_frame=\([0-9]*\).*/\1/p' "$out/uart-$board.txt") | $((pc / 100)).$(printf %02d $((pc % 100))) | $(get parse_instructions) | $(get player_new_instructions) | $(get stack_bytes_used) | $(get state_bytes) |"
    done
    echo
    # Per-pose decode cost of one clip on every board's core, frames and 50 Hz sample_at.
    pose_cost_table() {
        local clip=$1 tag=$2
        echo "| core | board | mode | instructions/pose | instructions/channel/pose | worst pose | predicted/pose (\`mocap target cost\`) | playback stack B | state B (`Player<N>`, N the clip needs) | stack used B |"
        echo "|---|---|---|---|---|---|---|---|---|---|"
        for board in $(mocap_boards); do
            core=$(mocap_board_core "$board")
            for mode in frames:0 "sample_at 50 Hz":20000; do
                name=${mode%%:*}; us=${mode##*:}
                extra=(); [ "$us" != 0 ] && extra=(--sample-us "$us")
                bash scripts/firmware.sh run --board "$board" --clip "$clip" --icount "${extra[@]}" \
                    2>>"$log" >"$out/uart-$tag-$board-$us.txt" \
                    || { echo "bench.sh: firmware run on $board ($name) failed; last lines of $log:" >&2; tail -n 25 "$log" >&2; exit 1; }
                line=$(grep '^# decode_instructions_total=' "$out/uart-$tag-$board-$us.txt")
                per=$(sed -n 's/.* per_\(frame\|sample\)=\([0-9]*\).*/\2/p' <<<"$line")
                pc=$(sed -n 's/.* per_channel_x100=\([0-9]*\).*/\1/p' <<<"$line")
                worst=$(sed -n 's/.* max_\(frame\|sample\)=\([0-9]*\).*/\2/p' <<<"$line")
                stack=$(sed -n 's/^# stack_bytes_used=\([0-9]*\).*/\1/p' "$out/uart-$tag-$board-$us.txt")
                pstack=$(sed -n 's/^# .*playback_stack_bytes=\([0-9]*\).*/\1/p' "$out/uart-$tag-$board-$us.txt")
                # The model's figures for the board's chip (same name): instructions/pose, state.
                read -r predicted state < <("$mocap" target cost "$clip" --target "$board" | awk -v b="$board" '$1 == b { print $3, $7 }')
                [ "$us" = 0 ] || predicted="-"
                echo "| $core | $board | $name | $per | $((pc / 100)).$(printf %02d $((pc % 100))) | $worst | $predicted | $pstack | $state | $stack |"
            done
        done
        echo
    }
    echo "## index decode cost per pose, frames and sample_at, $(basename "$clip_src") at 1°"
    echo
    pose_cost_table "$out/clip.mcb" idx
    pca_src="$corpus/cmu/35_01.bvh"
    mocap_logged "$log" "$mocap" encode "$pca_src" -o "$out/pca.mcb" --codec pca-spline --max-error 50mm+arms:10mm
    echo "## pca-spline decode cost in QEMU (-icount shift=0), $(basename "$pca_src") at 50 mm + ARMS 10 mm, $(stat -c %s "$out/pca.mcb") bytes"
    echo
    pose_cost_table "$out/pca.mcb" pca
    mocap_logged "$log" "$mocap" encode "$pca_src" -o "$out/pred.mcb" --codec predictive --max-error 1deg
    echo "## predictive decode cost in QEMU (-icount shift=0), $(basename "$pca_src") at 1°, $(stat -c %s "$out/pred.mcb") bytes"
    echo
    pose_cost_table "$out/pred.mcb" pred
    echo "## Flash (opt-level = \"s\", LTO), same clip"
    echo
    echo '```text'
    for board in $(mocap_boards); do
        bash scripts/firmware.sh size --board "$board" --clip "$out/clip.mcb" 2>>"$log" | tr '\n' ' '
        echo
    done
    echo '```'
    echo
}

if [ "${1:-}" = --decode ]; then
    shift
    decode_part "$@"
    exit 0
fi

echo "## Rate–distortion (mocap bench)"
echo
/usr/bin/time -f "encode wall time for the whole run: %e s" \
    "$mocap" bench "$corpus/cmu" "$corpus/iclone-cmu" \
    --codec index --codec pca-spline --codec predictive --codec auto \
    --max-error 1deg --max-error 0.25deg --max-error 20mm --max-error 50mm+arms:10mm \
    --json "$out/bench.json" 2>"$out/bench.log"
tail -1 "$out/bench.log"
echo
echo "## pca-spline encode time against clip length (05_04 cut to N frames, 50mm+arms:10mm)"
echo
echo "| frames | seconds | bytes |"
echo "|---|---|---|"
for n in 150 300 600 1200; do
    awk -v n="$n" '/^Frames:/ {print "Frames: " n; next} /^Frame Time/ {print; body=1; next} body {if (k++ < n) print; next} {print}' \
        "$corpus/cmu/05_04.bvh" >"$out/cut.bvh"
    mocap_logged "$log" /usr/bin/time -f %e -o "$out/time" "$mocap" encode "$out/cut.bvh" -o "$out/cut.mcb" \
        --codec pca-spline --max-error 50mm+arms:10mm
    echo "| $n | $(cat "$out/time") | $(stat -c %s "$out/cut.mcb") |"
done
echo

echo "## Servo clips (mocap encode --rig assets/rigs/cmu_upper_body.toml, 16 servos)"
echo
echo '```text'
for f in 35_01 05_04; do
    for b in 0.5deg 2deg; do
        for c in index pca-spline predictive; do
            "$mocap" encode "$corpus/cmu/$f.bvh" --rig assets/rigs/cmu_upper_body.toml -o "$out/servo.mcb" \
                --codec "$c" --max-error "$b" 2>>"$log" | sed "s|^$out/servo.mcb: |$f @ $b: |"
        done
    done
done
echo '```'
echo

decode_part "$@"

# The show files read ${MOCAP_CORPUS:-…} from their own folder: give them the corpus absolute.
corpus_abs=$(cd "$corpus" && pwd)
echo "## Shows (mocap show build assets/shows/S.toml -o S.mcb)"
echo
echo '```text'
for s in cmu_servo iclone_motion iclone_motion_boneroot; do
    MOCAP_CORPUS="$corpus_abs" "$mocap" show build "assets/shows/$s.toml" -o "$out/$s.mcb" 2>>"$log"
done
echo '```'
echo
echo "## index table pools of the iclone shows (cargo run --release -p mocap-encoder --example show_pools -- S.mcb)"
echo
for s in iclone_motion iclone_motion_boneroot; do
    "$show_pools" "$out/$s.mcb"
    echo
done
echo "## Blend safety (cargo test --release -p mocap-tests --test show_blend_safety -- --nocapture)"
echo
echo '```text'
MOCAP_CORPUS="$corpus_abs" mocap_logged "$log" cargo test --release -q -p mocap-tests --test show_blend_safety -- --nocapture
grep -oE '(cmu_servo|demo): .*' "$log" | tail -n 8
echo '```'

echo
echo "## The show on the microcontroller (cargo test --release -p mocap-tests --test qemu_show -- --nocapture)"
echo
echo '```text'
mocap_logged "$log" cargo test --release -q -p mocap-tests --test qemu_show -- --nocapture
grep -E '^(microbit|lm3s6965|mps2-an386) [a-z]+: # (mode=show|show_ticks|blend_ticks|plain_ticks|stack)' "$log" || true
echo '```'
echo
echo "## Show firmware flash (scripts/firmware.sh size --board B --clip firmware-example/clips/demo_show.mcb --servo maestro)"
echo
echo '```text'
for b in microbit lm3s6965; do
    printf '%s: ' "$b"
    bash scripts/firmware.sh size --board "$b" --clip firmware-example/clips/demo_show.mcb --servo maestro 2>>"$log" \
        | grep -E '^(flash_bytes|flash_without_clip_bytes)=' | tr '\n' ' '
    echo
done
echo '```'
echo
echo "## Clock following (cargo test --release -p mocap-tests --test show_clock -- --nocapture)"
echo
echo '```text'
mocap_logged "$log" cargo test --release -q -p mocap-tests --test show_clock -- --nocapture
grep -E '^clock ' "$log" || true
echo '```'

echo
echo "## Readers: throughput and a folder of 500 files (encoder/examples/read_folder.rs)"
echo
# 500 files made of the corpus' BVH and AMC files (links, each AMC beside its ASF), read the way
# every command reads a folder; then the same folder through `mocap bench` (index, 1°).
cargo build --release -q -p mocap-encoder --example read_folder
read_folder="${CARGO_TARGET_DIR:-target}/release/examples/read_folder"
folder="$out/folder500"
rm -rf "$folder"
mkdir -p "$folder"
mapfile -t sources < <(find "$corpus_abs/cmu" "$corpus_abs/cmu-long" "$corpus_abs/iclone-cmu" "$corpus_abs/asf-amc" \
    \( -name '*.bvh' ! -name '*other_converter*' -o -name '*.amc' \) | sort)
for a in "$corpus_abs"/asf-amc/*.asf; do ln -s "$a" "$folder/"; done
for i in $(seq 0 499); do
    src="${sources[$((i % ${#sources[@]}))]}"
    base="$(basename "$src")"
    ln -s "$src" "$folder/${base%.*}_$i.${base##*.}"
done
echo '```text'
"$read_folder" "$corpus_abs/cmu" "$corpus_abs/cmu-long" "$corpus_abs/iclone-cmu" "$corpus_abs/asf-amc"
echo "-- the folder of 500:"
"$read_folder" "$folder"
/usr/bin/time -f "mocap bench (index, 1deg) over the 500 files: %e s wall, %M KB peak RSS" \
    "$mocap" bench "$folder" --codec index --max-error 1deg 2>&1 >/dev/null | tail -1
echo '```'
echo
baselines_part "$mocap" "$out"
