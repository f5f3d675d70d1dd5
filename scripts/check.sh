#!/usr/bin/env bash
# The static checks that CI runs before the tests (scripts/test.sh runs this first):
#   fmt           cargo fmt --check: the workspace, firmware-example/ and its real boards' crates,
#                 decoder-nostd/fuzz/
#   clippy        cargo clippy --workspace --all-targets -- -D warnings
#   fuzz-clippy   the same for decoder-nostd/fuzz (its own workspace)
#   boards        the board table (scripts/boards.sh) names the memory maps build.rs uses
#   fw-clippy-B   cargo clippy -- -D warnings of the firmware for board B, in each build mode
#                 (frames, sample, servo, stream), through scripts/toolchain.sh's route
#   hw-clippy-B   the same for a real board's crate (scripts/boards.sh MOCAP_HW_BOARD_TABLE,
#                 firmware-example/pico/), in each output mode (pca9685, pwm)
#   hw-build-B    scripts/firmware.sh build --board B: the real board's ELF and its UF2 (or .bin),
#                 with the default clip and with the shipped show (its show mode)
#   uf2           the tests of scripts/uf2.rs (rustc --test)
#   nostd-...     mocap-decoder on thumbv6m-none-eabi with no default features, then each codec
#                 feature alone, entropy, and defmt; mocap-servo with no default features and pca9685
#   panic-B       the firmware ELFs of board B (scripts/firmware.sh build, every mode) have no panic machinery
#                 (core::panicking::*, panic_fmt, panic_bounds_check, *_fail) except the call
#                 sites listed, each with why it cannot fire, in scripts/panic-allowlist.txt
#
#   bash scripts/check.sh [STEP-PREFIX...]     # all steps, or those whose name starts so
#
# Each step prints its name, ok/FAILED and its time; a failed step prints why (the last lines
# of its log, target/check/<step>.log) and the run goes on, so one run reports every failure.
# The last line is `checks: N passed, N failed`; the exit code is 1 if any step failed.
set -euo pipefail
# shellcheck source=scripts/toolchain.sh
source "$(dirname "${BASH_SOURCE[0]}")/toolchain.sh"
cd "$MOCAP_REPO_ROOT"

LOG_DIR="$MOCAP_REPO_ROOT/target/check"
mkdir -p "$LOG_DIR"
ALLOWLIST="$MOCAP_REPO_ROOT/scripts/panic-allowlist.txt"
NOSTD_TARGET=thumbv6m-none-eabi
FILTER=("$@")
PASSED=0
FAILED=()

wanted() {
    [ "${#FILTER[@]}" -eq 0 ] && return 0
    local f
    for f in "${FILTER[@]}"; do
        [[ "$1" == "$f"* ]] && return 0
    done
    return 1
}

# step NAME CMD...: runs CMD with its output in target/check/NAME.log.
step() {
    local name="$1" t0=$SECONDS rc=0
    shift
    wanted "$name" || return 0
    printf 'check: %-34s ' "$name"
    : >"$LOG_DIR/$name.log"
    MOCAP_LOG_TAIL=40 mocap_logged "$LOG_DIR/$name.log" "$@" 2>"$LOG_DIR/$name.why" || rc=$?
    if [ "$rc" -eq 0 ]; then
        printf 'ok (%ss)\n' "$((SECONDS - t0))"
        PASSED=$((PASSED + 1))
    else
        printf 'FAILED (%ss)\n' "$((SECONDS - t0))"
        sed 's/^/    /' "$LOG_DIR/$name.why"
        FAILED+=("$name")
    fi
}

# ---- fmt, clippy
fmt_all() {
    local rc=0
    cargo fmt --all --check || rc=1
    cargo fmt --manifest-path firmware-example/Cargo.toml --check || rc=1
    cargo fmt --manifest-path decoder-nostd/fuzz/Cargo.toml --check || rc=1
    local b
    for b in $(mocap_hw_boards); do
        cargo fmt --manifest-path "firmware-example/$(mocap_hw_board_field "$b" 3)/Cargo.toml" --check || rc=1
    done
    [ "$rc" -eq 0 ] || echo "formatting differs (above): run cargo fmt in the crate named"
    return "$rc"
}

# ---- the board table against build.rs
boards_agree() {
    local b mem rc=0
    for b in $(mocap_boards); do
        mem="$(mocap_board_memory "$b")"
        if [ ! -f "firmware-example/$mem" ]; then
            echo "board $b: memory map firmware-example/$mem does not exist"
            rc=1
        fi
        # build.rs: ("board-B", "memory", ...) on consecutive lines (rustfmt's layout) or one.
        if ! tr -d ' \n' <firmware-example/build.rs | grep -qF "(\"board-$b\",\"$mem\","; then
            echo "board $b: firmware-example/build.rs does not map feature board-$b to $mem"
            rc=1
        fi
        if ! grep -q "^board-$b = " firmware-example/Cargo.toml; then
            echo "board $b: firmware-example/Cargo.toml has no feature board-$b"
            rc=1
        fi
    done
    return "$rc"
}

# ---- firmware clippy: every mode of one board (the mode's constants change what clippy sees)
fw_clippy() {
    local board="$1" target mode rc=0
    target="$(mocap_board_target "$board")"
    mocap_toolchain_setup "$target" || return 1
    for mode in "" MOCAP_SAMPLE_US=20000 MOCAP_SERVO=pca9685 MOCAP_STREAM=1; do
        echo "== mode: ${mode:-frames}"
        (
            cd firmware-example
            # scripts/firmware.sh's target dir, shared by every board: the host side (the build
            # script and mocap-encoder) is compiled once for clippy and the builds. (A build after
            # clippy reruns the build script with its own modes and relinks the ELF: seconds.)
            export MOCAP_SAMPLE_US="" MOCAP_SERVO="" MOCAP_STREAM="" CARGO_TARGET_DIR="target/fw"
            [ -z "$mode" ] || export "${mode?}"
            mocap_cargo "$target" clippy --release --no-default-features --features "board-$board" \
                -- -D warnings
        ) || { echo "clippy failed for board $board, mode ${mode:-frames}"; rc=1; }
    done
    return "$rc"
}

# ---- a real board's crate: clippy in each output mode (MOCAP_SERVO)
hw_clippy() {
    local board="$1" target crate mode rc=0
    target="$(mocap_hw_board_field "$board" 2)"
    crate="$(mocap_hw_board_field "$board" 3)"
    mocap_toolchain_setup "$target" || return 1
    for mode in pca9685 pwm; do
        echo "== output: $mode"
        (
            cd "firmware-example/$crate"
            # The QEMU firmware's target dir (scripts/firmware.sh shares it too).
            export MOCAP_SERVO="$mode" CARGO_TARGET_DIR="../target/fw"
            mocap_cargo "$target" clippy --release -- -D warnings
        ) || { echo "clippy failed for board $board, output $mode"; rc=1; }
    done
    return "$rc"
}

hw_build() {
    echo "== the default clip"
    bash scripts/firmware.sh build --board "$1"
    echo "== the show (firmware-example/clips/demo_show.mcb): the show mode"
    bash scripts/firmware.sh build --board "$1" --clip firmware-example/clips/demo_show.mcb
}

uf2_tests() {
    local bin="$MOCAP_REPO_ROOT/target/check/uf2-test"
    rustc --edition 2021 --test scripts/uf2.rs -o "$bin" && "$bin"
}

# ---- no_std builds
nostd_build() {
    local package="$1"
    shift
    mocap_toolchain_setup "$NOSTD_TARGET" || return 1
    CARGO_TARGET_DIR="$MOCAP_REPO_ROOT/target/check-nostd" \
        mocap_cargo "$NOSTD_TARGET" build -p "$package" --no-default-features "$@"
}

# ---- panic machinery in the firmware ELF
# Symbols that are panic machinery (demangled names).
PANIC_RE='core::panicking::|panic_fmt|panic_bounds_check|unwrap_failed|expect_failed|_index_len_fail|slice_index_order_fail|len_mismatch_fail|panic_const_|panic_nounwind|rust_begin_unwind'

# Call sites into panic machinery from outside it, one per line:
#   SYMBOL <- ORIGIN<TAB>ADDRESS<TAB>LOCATION
# ORIGIN is the innermost frame (of the inlining chain at the call) outside Rust's own library,
# const generic arguments removed (`Player<320>` -> `Player`); LOCATION is its file:line.
panic_call_sites() {
    local elf="$1" dis
    dis="$(mktemp)"
    llvm-objdump -d -C --no-show-raw-insn "$elf" >"$dis"
    # Two passes over the listing: the first maps function addresses to names (RISC-V calls are
    # `auipc REG, HI` + `jalr/jr LO(REG)` pairs that ld.lld leaves unrelaxed and llvm-objdump
    # does not resolve), the second finds the calls.
    awk -v re="$PANIC_RE" '
        function hex(s,   i, n) {
            n = 0; s = tolower(s)
            for (i = 1; i <= length(s); i++) n = n * 16 + index("0123456789abcdef", substr(s, i, 1)) - 1
            return n
        }
        FNR == NR {
            if (/^[0-9a-f]+ <.*>:$/) {
                name = $0; sub(/^[0-9a-f]+ </, "", name); sub(/>:$/, "", name)
                at[sprintf("%.0f", hex($1))] = name
            }
            next
        }
        /^[0-9a-f]+ <.*>:$/ {
            name = $0; sub(/^[0-9a-f]+ </, "", name); sub(/>:$/, "", name)
            if (name !~ /^(\$[dtx]|\.L)/) fn = name
            next
        }
        # Any instruction naming a panic symbol: bl, b.w, conditional tail branches (bhs.w), jal, ...
        /^ *[0-9a-f]+:[ \t]/ && match($0, /[\t ]0x[0-9a-f]+ <.*>/) {
            t = substr($0, RSTART + 1); sub(/^0x[0-9a-f]+ </, "", t)
            sub(/>[ \t]*(@.*)?$/, "", t); sub(/\+0x[0-9a-f]+$/, "", t)
            if (t ~ re && fn !~ re) { a = $1; sub(/:$/, "", a); print a "\t" t }
            next
        }
        # RISC-V: auipc REG, HI sets REG = pc + HI * 4096; jalr/jr LO(REG) jumps to REG + LO.
        /^ *[0-9a-f]+:[ \t]/ && $2 == "auipc" {
            r = $3; sub(/,$/, "", r); pc = $1; sub(/:$/, "", pc)
            hi[r] = (hex(pc) + $4 * 4096) % 4294967296
            next
        }
        /^ *[0-9a-f]+:[ \t]/ && ($2 == "jalr" || $2 == "jr") && match($NF, /^-?[0-9]+\([a-z0-9]+\)$/) {
            off = $NF; sub(/\(.*/, "", off); r = $NF; sub(/.*\(/, "", r); sub(/\)/, "", r)
            if (r in hi) {
                dest = sprintf("%.0f", (hi[r] + off) % 4294967296)
                t = (dest in at) ? at[dest] : ""
                if (t ~ re && fn !~ re) { a = $1; sub(/:$/, "", a); print a "\t" t }
            }
            next
        }' "$dis" "$dis" | sort -u | while IFS=$'\t' read -r addr sym; do
        local chain origin="" loc="" fnname file
        chain="$(llvm-symbolizer --inlining -C -e "$elf" "0x$addr")"
        # Pairs of lines: function, file:line:col (innermost first).
        while IFS= read -r fnname && IFS= read -r file; do
            [ -z "$fnname" ] && break
            case "$file" in
                */rustlib/src/*|*/library/core/*|*/library/compiler-builtins/*) continue ;;
            esac
            origin="$fnname"
            loc="${file#"$MOCAP_REPO_ROOT"/}"
            break
        done <<<"$chain"
        if [ -z "$origin" ]; then
            origin="$(head -n1 <<<"$chain")"
            loc="$(sed -n 2p <<<"$chain" | sed 's|.*/library/|library/|')"
        fi
        origin="$(sed -E 's/<[0-9]+>//g' <<<"$origin")"
        printf '%s <- %s\t0x%s\t%s\n' "$sym" "$origin" "$addr" "$loc"
    done
    rm -f "$dis"
}

# The firmware's build modes the panic check covers: each selects other code (build.rs consts).
PANIC_MODES=("" "--sample-us 20000" "--servo maestro" "--servo ssc32" "--servo pwm" "--servo pca9685" "--stream"
    "--clip firmware-example/clips/demo_show.mcb --servo maestro")

# panic_free BOARD: every mode's ELF of BOARD against the allowlist.
panic_free() {
    local board="$1" mode rc=0
    command -v llvm-objdump >/dev/null && command -v llvm-symbolizer >/dev/null && command -v llvm-nm >/dev/null \
        || mocap_ensure_packages llvm || return 1
    : >"$LOG_DIR/panic-sites-$board.txt"
    for mode in "${PANIC_MODES[@]}"; do
        # shellcheck disable=SC2086 # a mode is several words
        panic_free_elf "$board" $mode || rc=1
    done
    return "$rc"
}

# panic_free_elf BOARD [FIRMWARE-ARGS...]: one ELF (scripts/firmware.sh build --board BOARD ARGS).
panic_free_elf() {
    local board="$1" elf sites allowed unexpected syms
    shift
    echo "== board $board, mode: ${*:-frames}"
    elf="$(bash scripts/firmware.sh build --board "$board" "$@" | tail -n1)" || return 1
    echo "ELF: $elf"
    syms="$(llvm-nm -C --defined-only "$elf" | cut -d' ' -f3- | grep -E "$PANIC_RE" || true)"
    if [ -z "$syms" ]; then
        echo "no panic machinery"
        return 0
    fi
    printf 'panic machinery present:\n%s\n' "$(sed 's/^/  /' <<<"$syms")"
    sites="$(panic_call_sites "$elf")"
    printf 'call sites (symbol <- origin, address, source):\n%s\n' "$(sed 's/^/  /' <<<"$sites")"
    allowed="$(sed -e 's/[[:space:]]*#.*$//' -e '/^[[:space:]]*$/d' "$ALLOWLIST" | sort -u)"
    unexpected="$(cut -f1 <<<"$sites" | sort -u | comm -23 - <(printf '%s\n' "$allowed") || true)"
    printf '%s\n' "$sites" | cut -f1 | sort -u >>"$LOG_DIR/panic-sites-$board.txt"
    if [ -n "$unexpected" ]; then
        echo "board $board, mode ${*:-frames}: call sites into panic machinery that scripts/panic-allowlist.txt does not allow:"
        grep -F -f <(printf '%s\n' "$unexpected") <<<"$sites" | sed 's/^/  /'
        echo "remove them (get()/slice patterns/iterators instead of indexing, checked_* instead of / and %),"
        echo "or add the exact 'symbol <- origin' line with why it cannot fire to scripts/panic-allowlist.txt"
        return 1
    fi
    [ -n "$sites" ] || { echo "panic symbols without a call site from outside them: dead code kept by the linker?"; return 1; }
    echo "every call site is allowed (scripts/panic-allowlist.txt)"
}

# ---- the steps
step fmt fmt_all
step clippy cargo clippy --workspace --all-targets -- -D warnings
step fuzz-clippy cargo clippy --manifest-path decoder-nostd/fuzz/Cargo.toml --all-targets -- -D warnings
step boards boards_agree
for b in $(mocap_boards); do
    step "fw-clippy-$b" fw_clippy "$b"
done
for b in $(mocap_hw_boards); do
    step "hw-clippy-$b" hw_clippy "$b"
    step "hw-build-$b" hw_build "$b"
done
step uf2 uf2_tests
step nostd-decoder nostd_build mocap-decoder
for f in codec-index codec-pca-spline codec-predictive codec-pattern codec-rma entropy defmt; do
    step "nostd-decoder-$f" nostd_build mocap-decoder --features "$f"
done
step nostd-servo nostd_build mocap-servo
step nostd-servo-pca9685 nostd_build mocap-servo --features pca9685
for b in $(mocap_boards); do
    step "panic-$b" panic_free "$b"
done
# Allowances no board needs any more.
if wanted panic && [ -f "$ALLOWLIST" ]; then
    stale="$(sed -e 's/[[:space:]]*#.*$//' -e '/^[[:space:]]*$/d' "$ALLOWLIST" | sort -u \
        | comm -23 - <(cat "$LOG_DIR"/panic-sites-*.txt 2>/dev/null | sort -u) || true)"
    [ -z "$stale" ] || printf 'check: note: allowed in scripts/panic-allowlist.txt but found on no board (remove?):\n%s\n' \
        "$(sed 's/^/    /' <<<"$stale")"
fi

if [ "${#FAILED[@]}" -gt 0 ]; then
    echo "check: FAILED: ${FAILED[*]} (logs: target/check/)"
fi
echo "checks: $PASSED passed, ${#FAILED[@]} failed"
[ "${#FAILED[@]}" -eq 0 ]
