#!/usr/bin/env bash
# The decode cost model of `mocap encode --target` (encoder/src/target/), measured and fitted:
#
#   bash scripts/cost.sh [--boards "microbit lm3s6965 riscv-virt"] [--check-boards "mps2-an386"] [--write]
#   bash scripts/cost.sh --fit-only [--write]   (step 3 alone, on the last run's measurements)
#   bash scripts/cost.sh --resume [...]          (keeps measured.tsv's rows, measures the rest)
#   bash scripts/cost.sh --only rma [--write]    (one codec's clips only: its model refitted, every
#                                                 other model kept as shipped; the report goes to
#                                                 BENCHMARKS.md's bench:cost-rma block)
#
#  1. encodes two sets of clips from the corpus ($MOCAP_CORPUS, default ../shared/data) and
#     assets/ into target/cost/clips: the calibration set (the fit) and the validation set (held
#     out: files the fit never sees), every codec (and `index` in its fast layout, named
#     index-fast) at two bounds each; and takes played on (`mocap generate long`, so that
#     they repeat) as `rma` clips at two bounds (`rma`'s body is read by `pca-spline`'s model:
#     its clips fit only what repeated poses add);
#  2. runs every clip in QEMU with -icount shift=0 (scripts/firmware.sh run --icount) on each
#     board of --boards (fit and checked) and of --check-boards (checked only: a core the model
#     predicts from another core's fit, the M4F from the M3's), rows into target/cost/measured.tsv;
#     then every pca-spline and rma clip again with the smallest, the middle and the largest
#     Player<N> worth building for it (--player-words N, a seventh column: none, some, every
#     group cached);
#  3. `mocap target fit target/cost/measured.tsv` fits the model per core and codec on the
#     calibration rows and prints predicted against measured for every row, and the worst error
#     per set; with --write it rewrites encoder/src/target/calibration.rs (the coefficients the
#     encoder ships) and BENCHMARKS.md's block between `<!-- bench:cost -->` markers.
# Clips the example firmware's player cannot hold (a predictive clip needs 3 words of state per
# channel; the firmware has 320) are reported and not measured.
# Takes about 45 minutes on 2 cores (some 350 firmware builds and runs of ~5 s each).
set -euo pipefail
# shellcheck source=scripts/toolchain.sh
source "$(dirname "${BASH_SOURCE[0]}")/toolchain.sh"
cd "$MOCAP_REPO_ROOT"
corpus="${MOCAP_CORPUS:-../shared/data}"

boards="microbit lm3s6965 riscv-virt"
check_boards="mps2-an386"
write=""
fit_only=""
resume=""
only=""
while [ "$#" -gt 0 ]; do
    case "$1" in
        --boards) boards="$2"; shift 2 ;;
        --check-boards) check_boards="$2"; shift 2 ;;
        --write) write=1; shift ;;
        --fit-only) fit_only=1; shift ;;
        --resume) resume=1; shift ;;
        --only) only="$2"; shift 2 ;;
        -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
        *) echo "cost.sh: unknown argument '$1'" >&2; exit 2 ;;
    esac
done

[ -d "$corpus/cmu" ] || { echo "cost.sh: no corpus at $corpus (set MOCAP_CORPUS)" >&2; exit 2; }
cargo build --release -q -p mocap-cli
mocap="${CARGO_TARGET_DIR:-target}/release/mocap"
out=target/cost
mkdir -p "$out/clips"
tsv="$out/measured.tsv"
# set name input: one source of the calibration (fit) or validation (check) set.
sources=(
    "fit 05_04 $corpus/cmu/05_04.bvh"
    "fit 09_01 $corpus/cmu/09_01.bvh"
    "fit 16_07 $corpus/cmu/16_07.bvh"
    "fit 35_17 $corpus/cmu/35_17.bvh"
    "fit 002_01 $corpus/iclone-cmu/002_01.bvh"
    "fit 005_11 $corpus/iclone-cmu/005_11.bvh"
    "fit 007_03 $corpus/iclone-cmu/007_03.bvh"
    "fit 13_39 $corpus/asf-amc/13_39.amc"
    "fit demo assets/animatronic_demo.bvh"
    "fit 00_Walk1 $corpus/c3d/00_Walk1.c3d"
    "check 35_01 $corpus/cmu/35_01.bvh"
    "check 06_05 $corpus/cmu/06_05.bvh"
    "check 01_14 $corpus/cmu-long/01_14.bvh"
    "check 002_09 $corpus/iclone-cmu/002_09.bvh"
    "check 007_12 $corpus/iclone-cmu/007_12.bvh"
    "check 16_15 $corpus/asf-amc/16_15.amc"
    "check 01_Eb015pi $corpus/c3d/01_Eb015pi.c3d"
)
# set name input frames: a take played on to `frames` frames (its first frame dropped: CMU's
# reference pose), coded with `rma` only: its later playings are repeated clips.
repeating=(
    "fit demo2 assets/animatronic_demo.bvh 960"
    "fit 35_17x $corpus/cmu/35_17.bvh 600"
    "fit 09_01x $corpus/cmu/09_01.bvh 500"
    "fit 16_07x $corpus/cmu/16_07.bvh 1200"
    "fit 007_03x $corpus/iclone-cmu/007_03.bvh 600"
    "check 35_01x $corpus/cmu/35_01.bvh 1000"
    "check 06_05x $corpus/cmu/06_05.bvh 1000"
    "check 01_14x $corpus/cmu-long/01_14.bvh 4000"
)

# bounds INPUT CODEC: the codec's two bounds (marker clips take lengths only).
bounds() {
    case "$1:$2" in
        *.c3d:*) echo "5mm 50mm+arms:10mm" ;;
        *:index|*:index-fast) echo "1deg 20mm" ;;
        *:pca-spline|*:rma) echo "50mm+arms:10mm 20mm" ;;
        *:predictive) echo "1deg 0.25deg" ;;
    esac
}

# encode_clips: every source with every codec at its two bounds; sets clips=("set path" ...).
encode_clips() {
    echo "cost.sh: encoding the clips into $out/clips" >&2
    clips=()
    local s set name input codec b tag clip frames
    mkdir -p "$out/inputs"
    [ -z "$only" ] || [ "$only" = rma ] || repeating=()
    for s in "${repeating[@]}"; do
        read -r set name input frames <<<"$s"
        local long="$out/inputs/$name.bvh"
        if [ ! -s "$long" ] || [ "$input" -nt "$long" ]; then
            "$mocap" generate long --from "$input" --skip 1 --frames "$frames" -o "$long" >/dev/null 2>>"$out/encode.log" \
                || { echo "cost.sh: playing $input on to $frames frames failed; see $out/encode.log" >&2; exit 1; }
        fi
        sources+=("$set $name $long rma")
    done
    for s in "${sources[@]}"; do
        read -r set name input codecs <<<"$s"
        for codec in ${codecs:-index pca-spline predictive index-fast}; do
            [ -z "$only" ] || [ "$codec" = "$only" ] || continue
            local args=(--codec "$codec")
            [ "$codec" = index-fast ] && args=(--codec index --index-layout fast)
            for b in $(bounds "$input" "$codec"); do
                tag="$(tr -c 'a-z0-9\n' '_' <<<"$b")"
                clip="$out/clips/${name}_${codec}_${tag}.mcb"
                if [ ! -s "$clip" ] || [ "$input" -nt "$clip" ]; then
                    "$mocap" encode "$input" "${args[@]}" --max-error "$b" -o "$clip" >/dev/null 2>>"$out/encode.log" \
                        || { echo "cost.sh: encoding $input ($codec, $b) failed; see $out/encode.log" >&2; exit 1; }
                fi
                clips+=("$set $clip")
            done
        done
    done
}

# figures LOG: the firmware's decode instructions per pose and playback stack, tab-separated.
figures() {
    printf '%s\t%s' \
        "$(sed -n 's/^# decode_instructions_total=.* per_frame=\([0-9]*\) .*/\1/p' <<<"$1")" \
        "$(sed -n 's/^# .*playback_stack_bytes=\([0-9]*\).*/\1/p' <<<"$1")"
}

# measure_board BOARD ONLY_CHECK: every clip (only the check set if ONLY_CHECK) on BOARD, rows
# appended to measured.tsv: board core set clip decode_per_pose playback_stack_bytes.
measure_board() {
    local board=$1 only_check=$2 core n=0 c set clip log words
    core="$(mocap_board_core "$board")"
    for c in "${clips[@]}"; do
        read -r set clip <<<"$c"
        [ -n "$only_check" ] && [ "$set" = fit ] && continue
        if [ -n "$resume" ] && awk -F'\t' -v b="$board" -v c="$clip" '$1 == b && $4 == c && NF == 6 || $1 == b && $4 == c && $0 !~ /_(pca-spline|rma)_/ { f = 1 } END { exit !f }' "$tsv"; then
            continue
        fi
        words=""
        if ! log="$(bash scripts/firmware.sh run --board "$board" --clip "$clip" --icount 2>>"$out/firmware.log")"; then
            # A clip the example firmware's 320-word player cannot hold runs again with the
            # Player<N> it needs (a seventh column), if the board's RAM holds one; any other
            # failure stops the run.
            if ! grep -q '^# error player:.*capacity' <<<"$log"; then
                echo "cost.sh: $clip on $board failed:" >&2
                grep '^#' <<<"$log" >&2 || true
                exit 1
            fi
            words="$("$mocap" target cost "$clip" --target "$board" | awk -v b="$board" '$1 == b { print $6 }')"
            [ -n "$words" ] || { echo "cost.sh: $clip on $board: no player size from mocap target cost" >&2; exit 1; }
            measure_player "$board" "$core" "$set" "$clip" "$words"
            n=$((n + 1))
            continue
        fi
        printf '%s\t%s\t%s\t%s\t%s\n' "$board" "$core" "$set" "$clip" "$(figures "$log")" >>"$tsv"
        n=$((n + 1))
    done
    echo "cost.sh: $board ($core): $n clips" >&2
}

# measure_player BOARD CORE SET CLIP WORDS: CLIP with a Player<WORDS>, a row with the seventh
# column player_words (skipped under --resume if measured). A player the board's RAM cannot hold
# (capacity_limit) runs where one can on the same core: the microbit's M0 as the lm3s6965
# firmware built for thumbv6m under `-cpu cortex-m0` (firmware.sh --m0; board lm3s6965-m0,
# the same instruction counts).
measure_player() {
    local board=$1 core=$2 set=$3 clip=$4 words=$5 label=$1 log
    local run=(--board "$board")
    if [ "$words" -gt "$(capacity_limit "$board")" ]; then
        [ "$core" = M0 ] || { echo "cost.sh: $clip on $board: a Player<$words> does not fit (not measured)" >&2; return 0; }
        label=lm3s6965-m0
        run=(--board lm3s6965 --m0)
    fi
    if [ -n "$resume" ] && awk -F'\t' -v b="$label" -v c="$clip" -v w="$words" '$1 == b && $4 == c && $7 == w { f = 1 } END { exit !f }' "$tsv"; then
        return 0
    fi
    log="$(bash scripts/firmware.sh run "${run[@]}" --clip "$clip" --icount --player-words "$words" 2>>"$out/firmware.log")" \
        || { echo "cost.sh: $clip on $label with Player<$words> failed:" >&2; grep '^#' <<<"$log" >&2 || true; exit 1; }
    printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$label" "$core" "$set" "$clip" "$(figures "$log")" "$words" >>"$tsv"
}

# measure_capacity BOARD ONLY_CHECK: every pca-spline and rma clip again with other players
# (`mocap target cost --capacities`): the smallest Player<N> (no group cached), the middle one
# and the one that caches every group, each that is not the firmware's default 320 words and
# is at most 2 000 words (measure_player: where the board's RAM holds it).
measure_capacity() {
    local board=$1 only_check=$2 core n=0 c set clip words all
    core="$(mocap_board_core "$board")"
    for c in "${clips[@]}"; do
        read -r set clip <<<"$c"
        [ -n "$only_check" ] && [ "$set" = fit ] && continue
        case "$clip" in *_pca-spline_* | *_rma_*) ;; *) continue ;; esac
        mapfile -t all < <("$mocap" target cost "$clip" --target "$board" --capacities | awk -v b="$board" '$1 == b { print $6 }')
        [ "${#all[@]}" -gt 0 ] || continue
        for words in $(printf '%s\n' "${all[0]}" "${all[$((${#all[@]} / 2))]}" "${all[$((${#all[@]} - 1))]}" | sort -un); do
            [ "$words" -ne 320 ] && [ "$words" -le 2000 ] || continue
            measure_player "$board" "$core" "$set" "$clip" "$words"
            n=$((n + 1))
        done
    done
    echo "cost.sh: $board ($core): $n pca-spline and rma runs with other players" >&2
}

# capacity_limit BOARD: the largest Player<N> the example firmware runs with on BOARD (its
# 16 KB microbit holds some 700 words beside the firmware's pose buffer; the others 2 000, the
# most measured).
capacity_limit() {
    case "$1" in
        microbit) echo 700 ;;
        *) echo 2000 ;;
    esac
}

# board_figures BOARD...: boards.tsv, per board: core, the player's state at the firmware's
# capacity (state_bytes, max_channels) and the decoder's code (firmware.sh size).
board_figures() {
    local board core log state max code
    printf 'board\tcore\tstate_bytes\tmax_channels\tdecoder_code_bytes\n' >"$out/boards.tsv"
    for board in "$@"; do
        core="$(mocap_board_core "$board")"
        log="$(bash scripts/firmware.sh run --board "$board" --icount 2>>"$out/firmware.log")" \
            || { echo "cost.sh: the demo clip on $board failed; see $out/firmware.log" >&2; exit 1; }
        state="$(sed -n 's/^# state_bytes=\([0-9]*\).*/\1/p' <<<"$log")"
        max="$(sed -n 's/^# board=.* max_channels=\([0-9]*\).*/\1/p' <<<"$log")"
        code="$(bash scripts/firmware.sh size --board "$board" 2>>"$out/firmware.log" | sed -n 's/^decoder_code_bytes=//p')"
        printf '%s\t%s\t%s\t%s\t%s\n' "$board" "$core" "$state" "$max" "$code" >>"$out/boards.tsv"
    done
}

if [ -z "$fit_only" ]; then
    encode_clips
    [ -n "$resume" ] && [ -s "$tsv" ] \
        || printf 'board\tcore\tset\tclip\tdecode_per_pose\tplayback_stack_bytes\n' >"$tsv"
    for b in $boards; do measure_board "$b" ""; done
    for b in $check_boards; do measure_board "$b" 1; done
    for b in $boards; do measure_capacity "$b" ""; done
    for b in $check_boards; do measure_capacity "$b" 1; done
fi
[ -s "$tsv" ] || { echo "cost.sh: no measurements in $tsv (run without --fit-only first)" >&2; exit 2; }
if [ -z "$fit_only" ] || [ ! -s "$out/boards.tsv" ]; then
    # shellcheck disable=SC2086 # board lists are words
    board_figures $boards $check_boards
fi

fit_args=("$tsv")
[ -n "$write" ] && fit_args+=(--write encoder/src/target/calibration.rs)
"$mocap" target fit "${fit_args[@]}" | tee "$out/fit.md"
if [ -n "$write" ]; then
    # shellcheck source=scripts/bench_splice.sh
    source scripts/bench_splice.sh
    splice_benchmarks "cost${only:+-$only}" "$out/fit.md"
    rustfmt --edition 2021 encoder/src/target/calibration.rs
    cargo build --release -q -p mocap-cli
    echo "cost.sh: wrote encoder/src/target/calibration.rs and BENCHMARKS.md (bench:cost); rebuild done" >&2
fi
