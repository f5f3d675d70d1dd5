#!/usr/bin/env bash
# Front door for the Cortex-M firmware example (firmware-example/): build, run in QEMU, size.
#
#   scripts/firmware.sh build --board B [--clip PATH.mcb] [--sample-us P]
#       Builds the firmware with the clip embedded. The last line on stdout is the ELF's path
#       (a copy per board, clip content and mode, so parallel callers never overwrite each
#       other's ELF). --sample-us P (µs, > 0) builds the sample mode (MOCAP_SAMPLE_US): the
#       firmware prints Player::sample_at at t = 0, P, 2P, … up to and including the first t
#       past the clip's duration instead of every frame.
#   scripts/firmware.sh run --board B [--clip PATH.mcb] [--sample-us P] [--servo OUTPUT] [--icount] [--timeout SECONDS]
#       A show (mocap show build) as --clip runs the show mode: commands over the UART (--input
#       FILE from `mocap send show.mcb --cues cues.txt --output FILE --fast`), SPEC.md §8.2.
#       --servo maestro|ssc32|pwm|pca9685 plays a servo clip (mocap encode --rig) at its rig's
#       rate through that output and prints one line per tick: Maestro bytes as hex, SSC-32
#       text, the 16 duties of the (recorded) PWM channels, the (recorded) PCA9685 I²C writes
#       (MOCAP_SERVO; see firmware-example/README.md).
#       --stream builds the streaming mode (MOCAP_STREAM=1): the firmware reads postcard + COBS +
#       CRC frames (SPEC.md §8, `mocap send`) from its UART and plays the uploaded clip or the
#       live poses on the figure (--figure) through --servo (default maestro);
#       --input FILE feeds FILE to the UART's receiver (QEMU's -serial stdio reads it from
#       stdin, only as fast as the UART takes bytes); the run ends when the servos are parked
#       after a Stop or after the uploaded clip.
#       Builds, then runs the ELF in QEMU headless: the UART on stdout, semihosting on. The exit
#       code is the firmware's (0 = every frame decoded), 124 on timeout (default 300 s).
#       --icount adds `-icount shift=0` so the instruction figures in the output are exact.
#       Runs that do not measure (no --icount, --m0, --stream, --entropy-bench) of a clip up to
#       64 KiB with the default figure (no --figure, --policy, --estop-at, --power) play it from
#       the clip slot (firmware-example/src/slot.rs): one build per board, the clip written into
#       a copy of the ELF; MOCAP_FW_EMBED=1 embeds it instead.
#       --figure RIG.toml sets the figure whose hard limits the firmware compiles in
#       (MOCAP_FIGURE; default assets/rigs/animatronic_demo.toml), --policy
#       refuse|clamp-if-inside|clamp what it does with a servo clip made for another rig
#       (MOCAP_POLICY; default clamp-if-inside); see firmware-example/README.md.
#       --stream-timeout MS: the streaming mode parks the servos after MS without an accepted
#       frame (MOCAP_STREAM_TIMEOUT_MS; default 500, 0 holds the last pose). --estop-at N
#       simulates the e-stop input pressed at output tick N (MOCAP_ESTOP_AT_TICK; QEMU's boards
#       have no button).
#       --entropy-bench builds the entropy-coder measurement instead of playback
#       (MOCAP_ENTROPY_BENCH=1, firmware-example/src/entropy_bench.rs): it decodes the rANS
#       streams build.rs encodes (SPEC.md §10) and prints `# entropy ...` lines with the
#       instructions per symbol (exact with --icount); the clip is not played.
#       --player-words N sizes the player's state, Player<N> (MOCAP_PLAYER_WORDS; default 320
#       words): a pca-spline player caches the groups that fit (mocap encode --target picks N).
#       --power SCHEDULE (with --servo): the servo mode samples at power levels (MOCAP_POWER,
#       SPEC.md §6.1), `mocap play --power`'s schedule: LEVEL[@TIME],… e.g. 3 or 0,3@2s,0@4.5s.
#       --m0 (with --board lm3s6965 only; a measurement, not a board): builds the lm3s6965
#       firmware for thumbv6m and runs it with `-cpu cortex-m0`, the M0's instructions with the
#       lm3s's 64 KB of RAM, for players the 16 KB microbit cannot hold (scripts/cost.sh; the
#       counts equal the microbit's where both run: 00_Walk1 pca-spline 5 mm, Player<320>,
#       346 401 instructions per pose on each).
#   scripts/firmware.sh size --board B [--clip PATH.mcb] [--sample-us P] [--servo OUTPUT] [--stream]
#       Builds, then prints key=value lines: text, data, bss, flash_bytes (text+data),
#       ram_static_bytes (data+bss), flash_clip_bytes, flash_without_clip_bytes,
#       decoder_code_bytes (code of mocap_decoder::*, crc::* and the firmware's out-of-line calls
#       into the decoder, where LTO inlines it), core_fmt_code_bytes (error messages only),
#       firmware_own_code_bytes. Stack use is printed by `run` (# stack_bytes_used=).
#   scripts/firmware.sh build --board pico|blackpill|esp32c3 [--clip PATH.mcb] [--servo pca9685|pwm] [--figure RIG.toml] [--policy P]
#       A real board (scripts/boards.sh, MOCAP_HW_BOARD_TABLE; its own crate, firmware-example/pico/,
#       firmware-example/blackpill/, firmware-example/esp32c3/): builds the ELF and, beside it, the
#       image to flash without a probe: pico a UF2 (scripts/uf2.rs), blackpill a flat .bin for USB
#       DFU (llvm-objcopy); esp32c3 none (espflash or probe-rs flash the ELF itself).
#       Prints the size lines of `size`, then uf2=PATH and uf2_bytes=N (bin=, bin_bytes=; none
#       for esp32c3), and last the ELF's path. --servo picks the output (MOCAP_SERVO: pca9685 on I²C, the default,
#       or pwm). A show as --clip builds the board's show mode (commands over its UART). `size` prints the same without the ELF's path; `run` is refused (no emulator:
#       flash it with probe-rs, the UF2 or DFU, firmware-example/pico/README.md).
#   scripts/firmware.sh boards
#       Lists the boards (the table in scripts/boards.sh): name, core, Rust target, emulator, its machine arguments,
#       memory map.
#
# Exit codes: 0 success; 1 the firmware reported a failure (run); 2 usage error or missing clip;
# 3 toolchain or build failure; 124 QEMU timed out.
#
# Boards (scripts/boards.sh): lm3s6965 (default; Cortex-M3), microbit (Cortex-M0), mps2-an386 (Cortex-M4F),
# riscv-virt (QEMU virt, RV32IMC); real boards, build and size only: pico (Raspberry Pi Pico, RP2040),
# blackpill (WeAct STM32F411CE), esp32c3 (ESP32-C3, RV32IMC, esp-hal).
# Clip: default firmware-example/clips/demo.mcb.
# Toolchain: scripts/toolchain.sh (rustup target if installed, else Debian's -Zbuild-std route);
# it installs missing packages itself (apt-get, root or sudo). Build/toolchain chatter goes to
# stderr; stdout holds only the results described above.
set -euo pipefail

# No `cd`: --clip and --input paths are the caller's.
# shellcheck source=scripts/toolchain.sh
source "$(dirname "${BASH_SOURCE[0]}")/toolchain.sh"
FW="$MOCAP_FIRMWARE_DIR"

die() {
    printf 'firmware.sh: error: %s\n' "$*" >&2
    exit 2
}

build_failed() {
    printf 'firmware.sh: error: %s\n' "$*" >&2
    exit 3
}

usage() {
    sed -n '2,/^$/p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
}

board_target() {
    mocap_hw_board_field "$1" 2 2>/dev/null || mocap_board_target "$1" 2>/dev/null \
        || die "unknown board '$1' (expected: $(mocap_boards | paste -sd' ') $(mocap_hw_boards | paste -sd' '))"
}

# ---- arguments
[ "$#" -ge 1 ] || { usage >&2; exit 2; }
CMD="$1"
shift
BOARD="$MOCAP_DEFAULT_BOARD"
CLIP="$FW/clips/demo.mcb"
ICOUNT=0
TIMEOUT=300
SAMPLE_US=""
SERVO=""
STREAM=""
INPUT=/dev/null
FIGURE="$MOCAP_REPO_ROOT/assets/rigs/animatronic_demo.toml"
POLICY=""
STREAM_TIMEOUT=""
ESTOP_AT=""
ENTROPY_BENCH=""
M0_ON_LM3S=""
PLAYER_WORDS=""
POWER=""
while [ "$#" -gt 0 ]; do
    case "$1" in
        --board) [ "$#" -ge 2 ] || die "--board needs a value"; BOARD="$2"; shift 2 ;;
        --board=*) BOARD="${1#*=}"; shift ;;
        --clip) [ "$#" -ge 2 ] || die "--clip needs a value"; CLIP="$2"; shift 2 ;;
        --clip=*) CLIP="${1#*=}"; shift ;;
        --sample-us) [ "$#" -ge 2 ] || die "--sample-us needs a value"; SAMPLE_US="$2"; shift 2 ;;
        --sample-us=*) SAMPLE_US="${1#*=}"; shift ;;
        --servo) [ "$#" -ge 2 ] || die "--servo needs a protocol"; SERVO="$2"; shift 2 ;;
        --servo=*) SERVO="${1#*=}"; shift ;;
        --stream) STREAM=1; shift ;;
        --input) [ "$#" -ge 2 ] || die "--input needs a file"; INPUT="$2"; shift 2 ;;
        --input=*) INPUT="${1#*=}"; shift ;;
        --figure) [ "$#" -ge 2 ] || die "--figure needs a rig file"; FIGURE="$2"; shift 2 ;;
        --figure=*) FIGURE="${1#*=}"; shift ;;
        --policy) [ "$#" -ge 2 ] || die "--policy needs a value"; POLICY="$2"; shift 2 ;;
        --policy=*) POLICY="${1#*=}"; shift ;;
        --stream-timeout) [ "$#" -ge 2 ] || die "--stream-timeout needs a value"; STREAM_TIMEOUT="$2"; shift 2 ;;
        --stream-timeout=*) STREAM_TIMEOUT="${1#*=}"; shift ;;
        --estop-at) [ "$#" -ge 2 ] || die "--estop-at needs a tick"; ESTOP_AT="$2"; shift 2 ;;
        --estop-at=*) ESTOP_AT="${1#*=}"; shift ;;
        --entropy-bench) ENTROPY_BENCH=1; shift ;;
        --m0) M0_ON_LM3S=1; shift ;;
        --player-words) [ "$#" -ge 2 ] || die "--player-words needs a value"; PLAYER_WORDS="$2"; shift 2 ;;
        --player-words=*) PLAYER_WORDS="${1#*=}"; shift ;;
        --power) [ "$#" -ge 2 ] || die "--power needs a schedule"; POWER="$2"; shift 2 ;;
        --power=*) POWER="${1#*=}"; shift ;;
        --icount) ICOUNT=1; shift ;;
        --timeout) [ "$#" -ge 2 ] || die "--timeout needs a value"; TIMEOUT="$2"; shift 2 ;;
        --timeout=*) TIMEOUT="${1#*=}"; shift ;;
        -h|--help) usage; exit 0 ;;
        *) die "unknown argument '$1' (see: scripts/firmware.sh --help)" ;;
    esac
done
case "$CMD" in
    build|run|size) ;;
    boards)
        for b in $(mocap_boards); do
            printf '%-11s %-4s %-28s %-20s %-36s %s\n' "$b" "$(mocap_board_core "$b")" "$(mocap_board_target "$b")" "$(mocap_board_qemu "$b")" \
                "$(mocap_board_qemu_args "$b")" "$(mocap_board_memory "$b")"
        done
        exit 0 ;;
    -h|--help|help) usage; exit 0 ;;
    *) die "unknown command '$CMD' (build, run, size, boards)" ;;
esac
TARGET="$(board_target "$BOARD")"
if [ -n "$M0_ON_LM3S" ]; then
    [ "$BOARD" = lm3s6965 ] || die "--m0 runs the lm3s6965 firmware on an M0 core: use --board lm3s6965"
    TARGET=thumbv6m-none-eabi
fi
HW_CRATE="$(mocap_hw_board_field "$BOARD" 3 2>/dev/null || true)"
if [ -n "$HW_CRATE" ]; then
    [ "$CMD" = run ] && die "board $BOARD is real hardware, not emulated: build it and flash the ELF (probe-rs) or its image (firmware-example/$HW_CRATE/README.md)"
    [ -z "$SAMPLE_US$STREAM$STREAM_TIMEOUT$ESTOP_AT$ENTROPY_BENCH$PLAYER_WORDS$POWER" ] \
        || die "board $BOARD takes --clip, --servo, --figure and --policy only"
    [ "$ICOUNT" -eq 0 ] && [ "$INPUT" = /dev/null ] || die "board $BOARD takes --clip, --servo, --figure and --policy only"
    case "$SERVO" in
        ""|pca9685|pwm) ;;
        *) die "--servo for board $BOARD must be pca9685 (default) or pwm, got '$SERVO'" ;;
    esac
fi
[[ "$TIMEOUT" =~ ^[0-9]+$ ]] || die "--timeout must be a whole number of seconds"
[ -r "$INPUT" ] || die "--input: cannot read $INPUT"
[ -n "$STREAM" ] && [ "$CMD" = run ] && [ "$INPUT" = /dev/null ] \
    && die "run --stream needs --input FILE (e.g. from: mocap send CLIP --output FILE --fast)"
[ -n "$STREAM" ] && [ -n "$SAMPLE_US" ] && die "--stream and --sample-us exclude each other"
[ -r "$FIGURE" ] || die "--figure: cannot read $FIGURE"
[ -z "$STREAM_TIMEOUT" ] || [[ "$STREAM_TIMEOUT" =~ ^[0-9]+$ ]] || die "--stream-timeout must be a whole number of ms"
[ -z "$ESTOP_AT" ] || [[ "$ESTOP_AT" =~ ^[0-9]+$ ]] || die "--estop-at must be a whole number of ticks"
[ -z "$POWER" ] || [ -n "$SERVO" ] || die "--power sets the servo mode's levels: give --servo too"
[ -z "$POWER" ] || [[ "$POWER" =~ ^[0-9@.,ms\ ]+$ ]] || die "--power must be LEVEL[@TIME],… (e.g. 3 or 0,3@2s), got '$POWER'"
[ -z "$PLAYER_WORDS" ] || [[ "$PLAYER_WORDS" =~ ^[1-9][0-9]*$ ]] || die "--player-words must be a whole number > 0"
case "$POLICY" in
    ""|refuse|clamp-if-inside|clamp) ;;
    *) die "--policy must be refuse, clamp-if-inside or clamp, got '$POLICY'" ;;
esac
case "$SERVO" in
    ""|maestro|ssc32|pwm|pca9685) ;;
    *) die "--servo must be maestro, ssc32, pwm or pca9685, got '$SERVO'" ;;
esac
if [ -n "$SAMPLE_US" ]; then
    [[ "$SAMPLE_US" =~ ^[0-9]+$ ]] && [ "$((10#$SAMPLE_US))" -gt 0 ] \
        || die "--sample-us must be a whole number of microseconds > 0"
    SAMPLE_US="$((10#$SAMPLE_US))"
fi

# ---- staging: the clip and the figure under names derived from their content (sets CLIP_SHA,
# STAGED_CLIP, FIGURE_SHA, STAGED_FIGURE)
stage_inputs() {
    if [ ! -f "$CLIP" ]; then
        if [ "$CLIP" = "$FW/clips/demo.mcb" ]; then
            die "default clip $CLIP not found: pass --clip PATH.mcb (made with: mocap encode --target mcu IN.bvh -o OUT.mcb)"
        fi
        die "clip not found: $CLIP"
    fi
    local clip_abs figure_abs
    clip_abs="$(cd "$(dirname "$CLIP")" && pwd)/$(basename "$CLIP")"
    CLIP_SHA="$(sha256sum "$clip_abs" | cut -c1-16)"
    figure_abs="$(cd "$(dirname "$FIGURE")" && pwd)/$(basename "$FIGURE")"
    FIGURE_SHA="$(sha256sum "$figure_abs" | cut -c1-12)"

    # The clip is staged under a name derived from its content: MOCAP_CLIP changes exactly when
    # the bytes do, so cargo reruns build.rs (rerun-if-env-changed) without relying on mtimes.
    mkdir -p "$FW/target/clips"
    STAGED_CLIP="$FW/target/clips/$CLIP_SHA.mcb"
    if ! cmp -s "$clip_abs" "$STAGED_CLIP" 2>/dev/null; then
        cp "$clip_abs" "$STAGED_CLIP.$$" && mv -f "$STAGED_CLIP.$$" "$STAGED_CLIP"
    fi

    # The figure too, under its content's name, keeping the file name for the build's messages.
    mkdir -p "$FW/target/figures/$FIGURE_SHA"
    STAGED_FIGURE="$FW/target/figures/$FIGURE_SHA/$(basename "$FIGURE")"
    if ! cmp -s "$figure_abs" "$STAGED_FIGURE" 2>/dev/null; then
        cp "$figure_abs" "$STAGED_FIGURE.$$" && mv -f "$STAGED_FIGURE.$$" "$STAGED_FIGURE"
    fi
}

# ---- the clip slot (firmware-example/src/slot.rs): `run` plays the clip from a build that does
# not embed it — one build per board, the clip, its sampling period and servo output written into
# the ELF's reserved flash — unless it measures (--icount, --m0), streams, benches the entropy
# coder, builds for another figure, policy, e-stop, stream timeout or power schedule (a build of
# its own anyway, and the slot build, with every output in it, takes ~35 % longer), the clip is
# over SLOT_BYTES, or MOCAP_FW_EMBED=1 asks for the embedding build. Rebuilding the firmware for
# every clip was most of the QEMU tests' time (a build ~10 s, a run ~1 s).
SLOT_BYTES=65536
USE_SLOT=""
if [ "$CMD" = run ] && [ "$ICOUNT" -eq 0 ] \
    && [ -z "$STREAM$ENTROPY_BENCH$M0_ON_LM3S$POLICY$ESTOP_AT$STREAM_TIMEOUT$POWER${MOCAP_FW_EMBED:-}" ] \
    && [ "$FIGURE" = "$MOCAP_REPO_ROOT/assets/rigs/animatronic_demo.toml" ] \
    && [ -f "$CLIP" ] && [ "$(stat -c %s "$CLIP")" -le "$SLOT_BYTES" ]; then
    USE_SLOT=1
fi

# le VALUE BYTES: VALUE as BYTES little-endian bytes on stdout.
le() {
    local v="$1" i
    for ((i = 0; i < $2; i++)); do
        # shellcheck disable=SC2059 # the format is the byte's octal escape
        printf "\\$(printf %03o "$((v & 255))")"
        v=$((v >> 8))
    done
}

# slot_fill ELF: a copy of the slot build ELF with the clip and the sampling period in its slot;
# prints the copy's path.
slot_fill() {
    local elf="$1" out at
    out="$(mktemp "${elf%.elf}.XXXXXX")" || build_failed "cannot create a copy of $elf"
    cp "$elf" "$out"
    at="$(LC_ALL=C grep -obUaF 'MOCAP-CLIP-SLOT:' "$out" | cut -d: -f1)"
    [[ "$at" =~ ^[0-9]+$ ]] || { rm -f "$out"; build_failed "no single clip slot in $elf"; }
    local servo=0 # MOCAP_SERVO's numbers (firmware-example/build.rs)
    case "$SERVO" in maestro) servo=1 ;; ssc32) servo=2 ;; pwm) servo=3 ;; pca9685) servo=4 ;; esac
    { le "$(stat -c %s "$CLIP")" 4; le "$servo" 1; le 0 3; le "${SAMPLE_US:-0}" 8; cat "$CLIP"; } \
        | dd of="$out" bs=4096 seek="$((at + 16))" oflag=seek_bytes conv=notrunc status=none \
        || { rm -f "$out"; build_failed "cannot write the clip into $out"; }
    printf '%s\n' "$out"
}

# ---- build: prints the ELF path
build() {
    local sha staged target_dir lock elf_dir elf figure_sha staged_figure sample_us="$SAMPLE_US" servo="$SERVO"
    stage_inputs
    sha="$CLIP_SHA" staged="$STAGED_CLIP" figure_sha="$FIGURE_SHA" staged_figure="$STAGED_FIGURE"
    if [ -n "$USE_SLOT" ]; then
        # The same build for every clip: the shipped demo embedded (unused), no sampling period,
        # no servo output (the slot's).
        sha="slot$SLOT_BYTES" staged="$FW/clips/demo.mcb" sample_us="" servo=""
    fi

    mocap_toolchain_setup "$TARGET" >&2 || build_failed "toolchain setup failed (log: $MOCAP_TOOLCHAIN_LOG)"
    mocap_toolchain_summary >&2

    # One target dir for every board (and for check.sh's firmware clippy): the host side of the
    # build (the build script and its dependencies, mocap-encoder among them) is compiled once,
    # not once per board; each board's code goes to the target's own subfolder.
    target_dir="$FW/target/fw"
    elf_dir="$FW/target/$BOARD/elf"
    elf="$elf_dir/mocap-firmware-$sha-f$figure_sha${POLICY:+-$POLICY}${STREAM_TIMEOUT:+-t$STREAM_TIMEOUT}${ESTOP_AT:+-e$ESTOP_AT}${sample_us:+-s$sample_us}${servo:+-$servo}${STREAM:+-stream}${ENTROPY_BENCH:+-entropy}${PLAYER_WORDS:+-w$PLAYER_WORDS}${POWER:+-p$(printf %s "$POWER" | sha256sum | cut -c1-8)}${M0_ON_LM3S:+-m0}.elf"
    mkdir -p "$elf_dir"
    lock="$FW/target/fw.lock"
    # One build at a time (cargo locks the shared target dir anyway); the ELF is copied out
    # under the lock.
    (
        flock -w 1800 9 || build_failed "timed out waiting for $lock"
        cd "$FW"
        MOCAP_CLIP="$staged" MOCAP_CLIP_SLOT="${USE_SLOT:+$SLOT_BYTES}" MOCAP_SAMPLE_US="$sample_us" MOCAP_SERVO="$servo" MOCAP_STREAM="$STREAM" \
            MOCAP_FIGURE="$staged_figure" MOCAP_FIGURE_NAME="$FIGURE" MOCAP_POLICY="$POLICY" \
            MOCAP_STREAM_TIMEOUT_MS="$STREAM_TIMEOUT" MOCAP_ESTOP_AT_TICK="$ESTOP_AT" MOCAP_ENTROPY_BENCH="$ENTROPY_BENCH" \
            MOCAP_PLAYER_WORDS="$PLAYER_WORDS" MOCAP_POWER="$POWER" CARGO_TARGET_DIR="$target_dir" mocap_cargo "$TARGET" build --release --no-default-features \
            --features "board-$BOARD" >&2 \
            || build_failed "cargo build failed for board $BOARD (clip $CLIP)"
        cp "$target_dir/$TARGET/release/mocap-firmware" "$elf.$$"
        mv -f "$elf.$$" "$elf"
    ) 9>"$lock" || exit $? # bash clears `set -e` inside $(build): pass the failure on
    printf '%s\n' "$elf"
}

# ---- a real board: its crate's ELF and the image beside it (UF2, a flat .bin for DFU, or none for
# `elf`); prints the size lines, uf2= and uf2_bytes= (or bin=, bin_bytes=) and (build) last the
# ELF's path
hw_build() {
    local crate target_dir elf_dir elf image lock family
    stage_inputs
    crate="$FW/$HW_CRATE"
    family="$(mocap_hw_board_field "$BOARD" 4)"
    mocap_toolchain_setup "$TARGET" >&2 || build_failed "toolchain setup failed (log: $MOCAP_TOOLCHAIN_LOG)"
    mocap_toolchain_summary >&2
    # The QEMU boards' target dir: the host side (build.rs with mocap-encoder) is shared, and so is
    # `core` of the target (build.rs, not rustflags, adds the board's link arguments).
    target_dir="$FW/target/fw"
    elf_dir="$FW/target/$BOARD/elf"
    elf="$elf_dir/mocap-firmware-$BOARD-$CLIP_SHA-f$FIGURE_SHA${POLICY:+-$POLICY}-${SERVO:-pca9685}.elf"
    case "$family" in
        bin) image="${elf%.elf}.bin" ;;
        elf) image="" ;;
        *) image="${elf%.elf}.uf2" ;;
    esac
    command -v llvm-objcopy >/dev/null 2>&1 || mocap_ensure_packages llvm >&2 || true
    mkdir -p "$elf_dir"
    lock="$FW/target/fw.lock"
    (
        flock -w 1800 9 || build_failed "timed out waiting for $lock"
        cd "$crate"
        MOCAP_CLIP="$STAGED_CLIP" MOCAP_SERVO="$SERVO" MOCAP_FIGURE="$STAGED_FIGURE" MOCAP_FIGURE_NAME="$FIGURE" \
            MOCAP_POLICY="$POLICY" CARGO_TARGET_DIR="$target_dir" mocap_cargo "$TARGET" build --release >&2 \
            || build_failed "cargo build failed for board $BOARD (clip $CLIP)"
        cp "$target_dir/$TARGET/release/mocap-firmware-$BOARD" "$elf.$$"
        mv -f "$elf.$$" "$elf"
        if [ "$family" = bin ]; then
            llvm-objcopy -O binary "$elf" "$image.$$" || build_failed "llvm-objcopy -O binary failed for $elf"
        elif [ -n "$image" ]; then
            "$(uf2_tool)" "$elf" "$image.$$" --family "$family" || build_failed "UF2 conversion failed for $elf"
        fi
        [ -z "$image" ] || mv -f "$image.$$" "$image"
    ) 9>"$lock" || exit $?
    size_report "$elf"
    [ -z "$image" ] || printf '%s=%s\n%s_bytes=%s\n' "${image##*.}" "$image" "${image##*.}" "$(stat -c %s "$image")"
    [ "$CMD" = size ] || printf '%s\n' "$elf"
}

# uf2_tool: prints the path of scripts/uf2.rs built for the host (rebuilt when the source is newer).
uf2_tool() {
    local src="$MOCAP_REPO_ROOT/scripts/uf2.rs" tool="$FW/target/uf2-tool/uf2" rustc
    if [ ! -x "$tool" ] || [ "$src" -nt "$tool" ]; then
        rustc="$(command -v rustc || printf '%s' "$MOCAP_DEBIAN_RUSTC")"
        mkdir -p "$(dirname "$tool")"
        "$rustc" --edition 2021 -O "$src" -o "$tool.$$" >&2 || build_failed "cannot build $src with $rustc"
        mv -f "$tool.$$" "$tool"
    fi
    printf '%s\n' "$tool"
}

run_qemu() {
    local elf="$1" rc=0 qemu_args
    read -r -a qemu_args <<<"$(mocap_board_qemu_args "$BOARD")"
    [ "$ICOUNT" -eq 1 ] && qemu_args+=(-icount shift=0)
    [ -n "$M0_ON_LM3S" ] && qemu_args=("${qemu_args[@]/cortex-m3/cortex-m0}")
    # No monitor, no display; UART0 (serial0) on stdout, its receiver fed from --input (stdin
    # of QEMU; /dev/null by default, never the caller's terminal).
    timeout -k 10 "$TIMEOUT" "$(mocap_board_qemu "$BOARD")" "${qemu_args[@]}" \
        -display none -monitor none -serial stdio \
        -semihosting-config enable=on,target=native \
        -kernel "$elf" <"$INPUT" || rc=$?
    if [ "$rc" -eq 124 ] || [ "$rc" -eq 137 ]; then
        printf 'firmware.sh: error: QEMU (%s) did not finish within %s s\n' "$BOARD" "$TIMEOUT" >&2
        exit 124
    fi
    exit "$rc"
}

# Sums of symbol sizes: decoder = mocap_decoder::* + the firmware's out-of-line calls into it
# (decoder_glue, where LTO inlines decoder code) + crc::* (the decoder's CRC dependency).
size_report() {
    local elf="$1" size_tool="" nm_tool=""
    if ! command -v llvm-size >/dev/null 2>&1 || ! command -v llvm-nm >/dev/null 2>&1; then
        mocap_ensure_packages llvm >&2 || true
    fi
    command -v llvm-size >/dev/null 2>&1 && [ -z "${MOCAP_SIZE_NO_LLVM:-}" ] && size_tool=llvm-size
    command -v llvm-nm >/dev/null 2>&1 && nm_tool=llvm-nm
    [ -z "$nm_tool" ] && command -v nm >/dev/null 2>&1 && nm_tool=nm

    local text data bss
    if [ -n "$size_tool" ]; then
        read -r text data bss _ < <("$size_tool" --format=berkeley "$elf" | sed -n 2p)
        # llvm-size counts NOBITS sections without the write flag as text (esp-hal's `.stack`,
        # `.rwdata_dummy`, `.rotext_dummy` on the ESP32-C3; the other boards have none): they
        # take no flash, so they go to bss like every NOBITS section (the readelf rules below).
        local misfiled
        misfiled="$(readelf -S -W "$elf" 2>/dev/null | awk '
            function hex(s,   i, n) {
                n = 0; s = tolower(s);
                for (i = 1; i <= length(s); i++) n = n * 16 + index("0123456789abcdef", substr(s, i, 1)) - 1;
                return n;
            }
            /^ *\[ *[0-9]+\]/ {
                sub(/^ *\[ *[0-9]+\] */, "");
                if ($2 == "NOBITS" && $7 ~ /A/ && $7 !~ /W/) s += hex($5);
            }
            END { printf "%d\n", s }')"
        text=$((text - ${misfiled:-0}))
        bss=$((bss + ${misfiled:-0}))
    elif command -v readelf >/dev/null 2>&1; then
        # Berkeley rules on the section headers: alloc+exec or read-only -> text, alloc+write
        # progbits -> data, nobits -> bss.
        read -r text data bss < <(readelf -S -W "$elf" | awk '
            function hex(s,   i, n) {   # portable (mawk has no strtonum)
                n = 0; s = tolower(s);
                for (i = 1; i <= length(s); i++) n = n * 16 + index("0123456789abcdef", substr(s, i, 1)) - 1;
                return n;
            }
            /^ *\[ *[0-9]+\]/ {
                sub(/^ *\[ *[0-9]+\] */, "");
                name=$1; type=$2; size=hex($5); flags=$7;
                if (flags !~ /A/) next;
                if (type == "NOBITS") bss += size;
                else if (flags ~ /W/) data += size;
                else text += size;
            }
            END { printf "%d %d %d\n", text, data, bss }')
    else
        die "neither llvm-size (package llvm) nor readelf (package binutils) is available"
    fi
    # riscv-rt's and esp-hal's `.heap` and `.stack` are NOBITS sections that only mark the free
    # RAM (up to the top of RAM): not static RAM, as cortex-m-rt's layout has none. esp-hal's
    # `.rotext_dummy` (ESP32-C3) only skips the flash-mapped rodata's span in the code's address
    # window: neither RAM nor flash of its own. (Its `.rwdata_dummy` stays: the data RAM that the
    # code copied to instruction RAM takes.) Both tools list sections with -A (name, size in
    # decimal).
    local reserved
    reserved="$("${size_tool:-size}" -A "$elf" 2>/dev/null | awk '$1 == ".stack" || $1 == ".heap" || $1 == ".rotext_dummy" { s += $2 } END { print s + 0 }')"
    bss=$((bss - reserved))
    printf 'board=%s target=%s\n' "$BOARD" "$TARGET"
    printf 'text=%s\ndata=%s\nbss=%s\n' "$text" "$data" "$bss"
    printf 'flash_bytes=%s\nram_static_bytes=%s\n' "$((text + data))" "$((data + bss))"
    local clip_bytes
    clip_bytes="$(stat -c %s "$CLIP")"
    printf 'flash_clip_bytes=%s\nflash_without_clip_bytes=%s\n' "$clip_bytes" "$((text + data - clip_bytes))"

    if [ -z "$nm_tool" ]; then
        printf 'decoder_code_bytes=unknown (no llvm-nm or nm)\n'
        return 0
    fi
    # "address size type name", sizes in decimal, names demangled. Only code (t/T) is
    # attributed: LTO merges constants into anonymous .rodata symbols that carry no crate name.
    "$nm_tool" -S -C --defined-only --radix=d "$elf" 2>/dev/null | awk '
        NF >= 4 && $3 ~ /^[tT]$/ {
            size = $2 + 0; name = $0; sub(/^[^ ]+ [^ ]+ [^ ]+ /, "", name);
            if (name ~ /mocap_decoder/) dec += size;
            else if (name ~ /decoder_glue/) glue += size;
            else if (name ~ /(^|[^a-z_])crc::/) crc += size;
            else if (name ~ /core::fmt|FmtAdapter/) fmt += size;
            else if (name ~ /^<?mocap_firmware(_[a-z0-9]+)?::|^main$/) fw += size;
        }
        END {
            printf "decoder_code_bytes=%d\n", dec + glue + crc;
            printf "decoder_code_breakdown mocap_decoder=%d decoder_glue=%d crc=%d\n", dec, glue, crc;
            printf "core_fmt_code_bytes=%d\n", fmt;
            printf "firmware_own_code_bytes=%d\n", fw;
        }'
}

case "$CMD" in
    build|size) if [ -n "$HW_CRATE" ]; then hw_build; exit 0; fi ;;
esac
case "$CMD" in
    build)
        build ;;
    run)
        ELF="$(build)"
        if [ -n "$USE_SLOT" ]; then
            ELF="$(slot_fill "$ELF")"
            trap 'rm -f "$ELF"' EXIT
        fi
        run_qemu "$ELF" ;;
    size)
        ELF="$(build)"
        size_report "$ELF" ;;
esac
