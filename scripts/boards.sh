# The firmware's boards: the one table that every script reads (through scripts/toolchain.sh,
# which sources this file). Sourced only: sets no shell options, never exits.
#
#   board       core  Rust target             QEMU machine arguments            memory map (from firmware-example/)
MOCAP_BOARD_TABLE='
microbit    M0    thumbv6m-none-eabi      -machine microbit                 memory/microbit.x
lm3s6965    M3    thumbv7m-none-eabi      -machine lm3s6965evb -cpu cortex-m3 ../memory.x
mps2-an386  M4F   thumbv7em-none-eabihf   -machine mps2-an386               memory/mps2-an386.x
riscv-virt  RV32  riscv32imc-unknown-none-elf -machine virt -bios none      memory/riscv-virt.x
'
# Order: the Cortex-M cores smallest first (the order of the benchmark tables), then the other
# ISA (RISC-V, so "bit-exact everywhere" covers a second instruction set). The default board:
MOCAP_DEFAULT_BOARD=lm3s6965

# mocap_boards: the board names, one per line.
mocap_boards() {
    awk 'NF { print $1 }' <<<"$MOCAP_BOARD_TABLE"
}

# _mocap_board_row BOARD: the table row of BOARD (fails with a message for an unknown board).
_mocap_board_row() {
    local row
    row="$(awk -v b="$1" '$1 == b' <<<"$MOCAP_BOARD_TABLE")"
    if [ -z "$row" ]; then
        printf 'boards: unknown board %s (expected one of: %s)\n' "$1" "$(mocap_boards | tr '\n' ' ')" >&2
        return 2
    fi
    printf '%s\n' "$row"
}

# _mocap_board_field BOARD AWK-PROGRAM: one field of BOARD's row.
_mocap_board_field() {
    local row
    row="$(_mocap_board_row "$1")" || return
    awk "$2" <<<"$row"
}

# mocap_board_core BOARD: M0, M3, M4F, RV32.
mocap_board_core() { _mocap_board_field "$1" '{ print $2 }'; }
# mocap_board_target BOARD: the Rust target.
mocap_board_target() { _mocap_board_field "$1" '{ print $3 }'; }
# mocap_board_qemu BOARD: the QEMU system emulator of the board's ISA.
mocap_board_qemu() {
    local target
    target="$(mocap_board_target "$1")" || return
    mocap_target_qemu "$target"
}
# mocap_target_qemu TARGET: the QEMU system emulator for a Rust target.
mocap_target_qemu() {
    case "$1" in
        riscv32*) printf 'qemu-system-riscv32\n' ;;
        *) printf 'qemu-system-arm\n' ;;
    esac
}
# mocap_board_qemu_args BOARD: the emulator's machine arguments.
mocap_board_qemu_args() {
    _mocap_board_field "$1" '{ s = ""; for (i = 4; i < NF; i++) s = s (s == "" ? "" : " ") $i; print s }'
}
# mocap_board_memory BOARD: the memory map, relative to firmware-example/ (build.rs picks it by
# the board's cargo feature; scripts/check.sh checks that the two agree).
mocap_board_memory() { _mocap_board_field "$1" '{ print $NF }'; }

# Real boards (no emulator): built and sized by scripts/firmware.sh, never run here. Each is its
# own crate under firmware-example/ (its own workspace and HAL). The last column is the file for
# flashing without a probe: a UF2 family ID (the RP2040 boot ROM's drag-and-drop), `bin`, the
# flat image from the start of flash (the STM32 ROM's USB DFU: dfu-util), or `elf`, none besides
# the ELF (the ESP32-C3: espflash and probe-rs write the ELF with the ESP-IDF bootloader).
#   board      Rust target                  crate (from firmware-example/)  image
MOCAP_HW_BOARD_TABLE='
pico       thumbv6m-none-eabi           pico                            0xe48bff56
blackpill  thumbv7em-none-eabihf        blackpill                       bin
esp32c3    riscv32imc-unknown-none-elf  esp32c3                         elf
'

# mocap_hw_boards: the real boards' names, one per line.
mocap_hw_boards() {
    awk 'NF { print $1 }' <<<"$MOCAP_HW_BOARD_TABLE"
}

# mocap_hw_board_field BOARD N: field N of a real board's row (empty, status 1, if BOARD is none).
mocap_hw_board_field() {
    local v
    v="$(awk -v b="$1" -v n="$2" '$1 == b { print $n }' <<<"$MOCAP_HW_BOARD_TABLE")"
    [ -n "$v" ] || return 1
    printf '%s\n' "$v"
}

# The Rust targets of all boards, space-separated.
MOCAP_FW_TARGETS="$(awk 'NF { printf "%s%s", sep, $3; sep = " " }' <<<"$MOCAP_BOARD_TABLE")"
