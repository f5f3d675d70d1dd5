#!/usr/bin/env bash
# Cross toolchain for the Cortex-M firmware (firmware-example/) and QEMU.
#
#   source scripts/toolchain.sh            # defines the functions below, installs nothing yet
#   mocap_toolchain_setup [TARGET...]      # ensure everything for these targets (default: every board's)
#   mocap_cargo TARGET ARGS...             # run cargo for TARGET the way this machine can:
#                                          #   mocap_cargo thumbv7m-none-eabi build --release
#   mocap_toolchain_summary                # print what was chosen
#   mocap_logged LOG CMD...                # run CMD with its output in LOG; on failure say so
#                                          #   and print LOG's last lines
#   mocap_explain_failure NAME [LOG]       # a failing command of the script prints what and why
#   the board table (scripts/boards.sh): mocap_boards, mocap_board_target B, ...
#
#   bash scripts/toolchain.sh [TARGET...]  # set up and print the summary
#
# Route per target, decided once by mocap_toolchain_setup:
#   rustup  - `rustup target list --installed` has the target: plain `cargo ... --target T`.
#             This is the ordinary way; on a machine with network run
#             `rustup target add thumbv6m-none-eabi thumbv7m-none-eabi thumbv7em-none-eabihf riscv32imc-unknown-none-elf`.
#   debian  - otherwise: Debian's matching rustc-web + cargo-web + rust-web-src, building `core`
#             from source: RUSTC_BOOTSTRAP=1 RUSTC=/usr/bin/rustc /usr/bin/cargo -Zbuild-std=core,
#             linked with ld.lld (Debian's lld).
# Always needed: qemu-system-arm (package qemu-system-arm); for RISC-V targets qemu-system-riscv32
# (package qemu-system-misc). ld.lld (package lld) for the debian route,
# and for `mocap_cargo TARGET clippy` Debian's clippy of the same rustc (package rust-web-clippy).
#
# Packages are installed with apt-get (as root, or through sudo), `apt-get update` only when
# something is missing, never interactively. Everything verbose goes to $MOCAP_TOOLCHAIN_LOG.
#
# Environment:
#   MOCAP_TOOLCHAIN_LOG     log file (default: firmware-example/target/toolchain.log)
#   MOCAP_TOOLCHAIN_ROUTE   force a route for every target: rustup | debian
#
# This file is the one set-up preamble of every script, sourced the same way by each:
#   source "$(dirname "${BASH_SOURCE[0]}")/toolchain.sh"
# It sets no shell options and never calls `exit` (functions `return` non-zero and print the
# reason on stderr).

MOCAP_REPO_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck source=scripts/boards.sh
source "$MOCAP_REPO_ROOT/scripts/boards.sh"
MOCAP_FIRMWARE_DIR="$MOCAP_REPO_ROOT/firmware-example"
: "${MOCAP_TOOLCHAIN_LOG:=$MOCAP_FIRMWARE_DIR/target/toolchain.log}"
MOCAP_DEBIAN_RUSTC=/usr/bin/rustc
MOCAP_DEBIAN_CARGO=/usr/bin/cargo
MOCAP_DEBIAN_RUST_SRC=/usr/lib/rustlib/src/rust/library

_mocap_log() {
    mkdir -p "$(dirname "$MOCAP_TOOLCHAIN_LOG")" 2>/dev/null || true
    printf '[%s] %s\n' "$(date '+%F %T')" "$*" >>"$MOCAP_TOOLCHAIN_LOG" 2>/dev/null || true
}

_mocap_err() {
    printf 'toolchain: error: %s\n' "$*" >&2
    _mocap_log "error: $*"
}

# Name of the variable holding the route of a target: thumbv7em-none-eabihf -> MOCAP_ROUTE_THUMBV7EM_NONE_EABIHF
_mocap_route_var() {
    local t="${1^^}"
    printf 'MOCAP_ROUTE_%s' "${t//[-.]/_}"
}

# mocap_logged LOG CMD...: runs CMD with stdout and stderr appended to LOG. On failure prints
# what failed, its exit code and the last lines of LOG on stderr, and returns CMD's exit code.
mocap_logged() {
    local log="$1" rc=0
    shift
    mkdir -p "$(dirname "$log")"
    printf '$ %s\n' "$*" >>"$log"
    "$@" >>"$log" 2>&1 || rc=$?
    if [ "$rc" -ne 0 ]; then
        printf 'error: `%s` failed (exit %s); last lines of %s:\n' "$*" "$rc" "$log" >&2
        tail -n "${MOCAP_LOG_TAIL:-25}" "$log" | sed 's/^/    /' >&2
    fi
    return "$rc"
}

# mocap_explain_failure NAME [LOG]: under `set -e`, a failing command of the calling script
# prints NAME, the line and the command, and LOG's last lines, before the script exits.
mocap_explain_failure() {
    _MOCAP_SCRIPT_NAME="$1"
    _MOCAP_SCRIPT_LOG="${2:-}"
    trap '_mocap_on_err $? $LINENO "$BASH_COMMAND"' ERR
}

_mocap_on_err() {
    printf '%s: error: line %s: `%s` failed (exit %s)\n' "$_MOCAP_SCRIPT_NAME" "$2" "$3" "$1" >&2
    if [ -n "$_MOCAP_SCRIPT_LOG" ] && [ -s "$_MOCAP_SCRIPT_LOG" ]; then
        printf '%s: last lines of %s:\n' "$_MOCAP_SCRIPT_NAME" "$_MOCAP_SCRIPT_LOG" >&2
        tail -n "${MOCAP_LOG_TAIL:-25}" "$_MOCAP_SCRIPT_LOG" | sed 's/^/    /' >&2
    fi
}

_mocap_pkg_installed() {
    [ "$(dpkg-query -W -f='${Status}' "$1" 2>/dev/null)" = "install ok installed" ]
}

# _mocap_unlisted_installed PKG...: for each installed package of the families of PKG (the
# name up to its first '-': qemu-system-arm → qemu-*) whose installed version no configured
# source offers, `name=version` with the highest version a source offers (nothing if none does).
_mocap_unlisted_installed() {
    local fams=() p name have best
    for p in "$@"; do fams+=("${p%%-*}"); done
    dpkg-query -W -f='${Package} ${Status}\n' 2>/dev/null \
        | awk '$NF == "installed" { print $1 }' \
        | while read -r name; do
            printf '%s\n' "${fams[@]}" | grep -qx -- "${name%%-*}" || continue
            have="$(dpkg-query -W -f='${Version}' "$name" 2>/dev/null)"
            apt-cache madison "$name" 2>/dev/null | awk -F' [|] ' -v v="$have" '$2 == v { f = 1 } END { exit !f }' && continue
            best="$(apt-cache madison "$name" 2>/dev/null | awk -F' [|] ' 'NR == 1 { print $2 }')"
            [ -n "$best" ] && printf '%s=%s\n' "$name" "$best"
        done
}

# mocap_ensure_packages PKG... : install the Debian packages that are missing.
mocap_ensure_packages() {
    local missing=() p
    for p in "$@"; do
        _mocap_pkg_installed "$p" || missing+=("$p")
    done
    [ "${#missing[@]}" -eq 0 ] && return 0

    if ! command -v apt-get >/dev/null 2>&1; then
        _mocap_err "missing packages (${missing[*]}) and no apt-get on this machine; install them yourself"
        return 1
    fi
    local sudo=()
    if [ "$(id -u)" -ne 0 ]; then
        if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
            sudo=(sudo -n)
        else
            _mocap_err "missing packages (${missing[*]}); run as root or with password-less sudo, or: apt-get install ${missing[*]}"
            return 1
        fi
    fi

    printf 'toolchain: installing %s (log: %s)\n' "${missing[*]}" "$MOCAP_TOOLCHAIN_LOG" >&2
    _mocap_log "installing: ${missing[*]}"
    local lock="${TMPDIR:-/tmp}/mocap-toolchain-apt.lock" rc=0
    # Serialise concurrent callers (tests run in parallel); re-check under the lock.
    (
        if command -v flock >/dev/null 2>&1; then
            exec 9>"$lock" && flock -w 900 9 || true
        fi
        still=()
        for p in "${missing[@]}"; do _mocap_pkg_installed "$p" || still+=("$p"); done
        [ "${#still[@]}" -eq 0 ] && exit 0
        export DEBIAN_FRONTEND=noninteractive
        apt_opts=(-y -q -o Dpkg::Use-Pty=0 -o DPkg::Lock::Timeout=600)
        "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get -q -o DPkg::Lock::Timeout=600 update \
            >>"$MOCAP_TOOLCHAIN_LOG" 2>&1 || exit 1
        if ! "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install "${apt_opts[@]}" "${still[@]}" \
            >>"$MOCAP_TOOLCHAIN_LOG" 2>&1; then
            # A machine may carry a package of the same family from a source it no longer
            # lists (seen: qemu-utils from bookworm-backports, which Breaks the archive's
            # qemu-system-common): once more with those taken to the archive's version.
            pins=()
            while read -r pin; do pins+=("$pin"); done < <(_mocap_unlisted_installed "${still[@]}")
            [ "${#pins[@]}" -gt 0 ] || exit 1
            _mocap_log "retrying with the archive's versions of: ${pins[*]}"
            printf 'toolchain: retrying with the archive'"'"'s versions of %s\n' "${pins[*]}" >&2
            "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install "${apt_opts[@]}" --allow-downgrades \
                "${still[@]}" "${pins[@]}" >>"$MOCAP_TOOLCHAIN_LOG" 2>&1 || exit 1
        fi
    ) || rc=$?
    if [ "$rc" -ne 0 ]; then
        _mocap_err "apt-get install ${missing[*]} failed; last lines of $MOCAP_TOOLCHAIN_LOG:"
        tail -n 15 "$MOCAP_TOOLCHAIN_LOG" >&2 2>/dev/null || true
        return 1
    fi
    for p in "${missing[@]}"; do
        if ! _mocap_pkg_installed "$p"; then
            _mocap_err "package $p is still not installed after apt-get install (log: $MOCAP_TOOLCHAIN_LOG)"
            return 1
        fi
    done
    _mocap_log "installed: ${missing[*]}"
    return 0
}

# True when rustup's active toolchain (as seen from firmware-example/) has TARGET installed.
_mocap_rustup_has_target() {
    command -v rustup >/dev/null 2>&1 || return 1
    command -v cargo >/dev/null 2>&1 || return 1
    (cd "$MOCAP_FIRMWARE_DIR" 2>/dev/null || cd "$MOCAP_REPO_ROOT"; rustup target list --installed 2>/dev/null) \
        | grep -qx -- "$1"
}

# mocap_toolchain_setup [TARGET...]: choose a route per target and install what is missing.
mocap_toolchain_setup() {
    local targets=("$@") t var route need_debian=0 hint=()
    [ "${#targets[@]}" -eq 0 ] && read -r -a targets <<<"$MOCAP_FW_TARGETS"
    _mocap_log "setup for: ${targets[*]}"

    for t in "${targets[@]}"; do
        var="$(_mocap_route_var "$t")"
        case "${MOCAP_TOOLCHAIN_ROUTE:-}" in
            rustup|debian) route="$MOCAP_TOOLCHAIN_ROUTE" ;;
            "") if _mocap_rustup_has_target "$t"; then route=rustup; else route=debian; hint+=("$t"); fi ;;
            *) _mocap_err "MOCAP_TOOLCHAIN_ROUTE must be rustup or debian, not '$MOCAP_TOOLCHAIN_ROUTE'"; return 1 ;;
        esac
        printf -v "$var" '%s' "$route"
        export "${var?}"
        [ "$route" = debian ] && need_debian=1
        _mocap_log "$t: route $route"
    done

    # The emulators of the targets' ISAs (Debian packs qemu-system-riscv32 in qemu-system-misc).
    local pkgs=(qemu-system-arm) qemus=(qemu-system-arm) q
    for t in "${targets[@]}"; do
        case "$t" in riscv32*) pkgs+=(qemu-system-misc); qemus+=(qemu-system-riscv32) ;; esac
    done
    [ "$need_debian" -eq 1 ] && pkgs+=(rustc-web cargo-web rust-web-src lld)
    mocap_ensure_packages "${pkgs[@]}" || return 1

    for q in "${qemus[@]}"; do
        if ! command -v "$q" >/dev/null 2>&1; then
            _mocap_err "$q is not on PATH even though its package is installed"
            return 1
        fi
    done
    if [ "$need_debian" -eq 1 ]; then
        local f
        for f in "$MOCAP_DEBIAN_RUSTC" "$MOCAP_DEBIAN_CARGO"; do
            [ -x "$f" ] || { _mocap_err "$f missing (package rustc-web/cargo-web)"; return 1; }
        done
        [ -d "$MOCAP_DEBIAN_RUST_SRC" ] || [ -d "$("$MOCAP_DEBIAN_RUSTC" --print sysroot)/lib/rustlib/src/rust/library" ] \
            || { _mocap_err "rust library source missing (package rust-web-src)"; return 1; }
        command -v ld.lld >/dev/null 2>&1 || { _mocap_err "ld.lld missing (package lld)"; return 1; }
        if [ "${#hint[@]}" -gt 0 ]; then
            MOCAP_TOOLCHAIN_HINT="no rustup target for ${hint[*]}: using Debian's rustc-web with -Zbuild-std=core (the ordinary way, with network: rustup target add ${hint[*]})"
            _mocap_log "$MOCAP_TOOLCHAIN_HINT"
        fi
    fi
    export MOCAP_TOOLCHAIN_READY=1
    return 0
}

# mocap_toolchain_route TARGET: prints rustup|debian (runs the setup for TARGET if needed).
mocap_toolchain_route() {
    local var
    var="$(_mocap_route_var "$1")"
    if [ -z "${!var:-}" ]; then
        mocap_toolchain_setup "$1" || return 1
    fi
    printf '%s\n' "${!var}"
}

# mocap_cargo TARGET CARGO-ARGS... [-- TOOL-ARGS...]: runs `cargo CARGO-ARGS... --target TARGET
# [-- TOOL-ARGS...]` through the route of TARGET (the target options go before a `--`, so
# `mocap_cargo T clippy -- -D warnings` works). Run it from the firmware directory (or pass
# --manifest-path).
mocap_cargo() {
    if [ "$#" -lt 2 ]; then
        _mocap_err "usage: mocap_cargo TARGET CARGO-SUBCOMMAND [ARGS...] [-- TOOL-ARGS...]"
        return 2
    fi
    local target="$1" route args=() tool=() seen=0 a
    shift
    for a in "$@"; do
        if [ "$seen" -eq 0 ] && [ "$a" = -- ]; then
            seen=1
        elif [ "$seen" -eq 0 ]; then
            args+=("$a")
        else
            tool+=("$a")
        fi
    done
    [ "$seen" -eq 1 ] && tool=(-- "${tool[@]}")
    set -- "${args[@]}"
    route="$(mocap_toolchain_route "$target")" || return 1
    _mocap_log "cargo ($route) $* --target $target ${tool[*]}"
    if [ "$route" = rustup ]; then
        cargo "$@" --target "$target" "${tool[@]}"
    else
        local upper="${target^^}" path="$PATH"
        upper="${upper//[-.]/_}"
        if [ "$1" = clippy ]; then
            # Debian's cargo-clippy/clippy-driver match its rustc; rustup's (first on PATH) do not.
            mocap_ensure_packages rust-web-clippy || return 1
            path="$(dirname "$MOCAP_DEBIAN_CARGO"):$PATH"
        fi
        env PATH="$path" RUSTC_BOOTSTRAP=1 RUSTC="$MOCAP_DEBIAN_RUSTC" \
            "CARGO_TARGET_${upper}_LINKER=ld.lld" \
            "$MOCAP_DEBIAN_CARGO" "$@" -Zbuild-std=core --target "$target" "${tool[@]}"
    fi
}

# mocap_toolchain_summary: one line saying which route builds which target, and the emulator.
mocap_toolchain_summary() {
    local t var rustup_t=() debian_t=() parts=() qemu_v v
    for t in $MOCAP_FW_TARGETS; do
        var="$(_mocap_route_var "$t")"
        case "${!var:-}" in
            rustup) rustup_t+=("$t") ;;
            debian) debian_t+=("$t") ;;
        esac
    done
    if [ "${#rustup_t[@]}" -gt 0 ]; then
        v="$(cd "$MOCAP_FIRMWARE_DIR" && rustc --version 2>/dev/null | cut -d' ' -f2)"
        parts+=("rustup ${v:-?} for ${rustup_t[*]}")
    fi
    if [ "${#debian_t[@]}" -gt 0 ]; then
        v="$("$MOCAP_DEBIAN_RUSTC" --version 2>/dev/null | cut -d' ' -f2)"
        parts+=("debian rustc-web ${v:-?} -Zbuild-std=core + ld.lld for ${debian_t[*]}")
    fi
    qemu_v="$(qemu-system-arm --version 2>/dev/null | head -n1 | sed 's/^QEMU emulator version //; s/ .*//')"
    local joined="" part
    for part in "${parts[@]}"; do joined="${joined:+$joined; }$part"; done
    printf 'toolchain: %s; qemu-system-arm %s (log: %s)\n' "$joined" "${qemu_v:-?}" "$MOCAP_TOOLCHAIN_LOG"
    [ "${#debian_t[@]}" -gt 0 ] && printf 'toolchain: hint: `rustup target add %s` is the ordinary way (needs network); plain cargo is then used\n' "${debian_t[*]}"
    return 0
}

# Run directly: set up and report.
if [ "${BASH_SOURCE[0]}" = "$0" ]; then
    set -euo pipefail
    for arg in "$@"; do
        case "$arg" in
            -h|--help) sed -n '2,/^$/p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
            thumb*|riscv32*) ;;
            *) printf 'toolchain: unknown argument %s (expected targets: %s)\n' "$arg" "$MOCAP_FW_TARGETS" >&2; exit 2 ;;
        esac
    done
    mocap_toolchain_setup "$@"
    mocap_toolchain_summary
fi
