#!/usr/bin/env bash
# Power levels (SPEC.md §6.1): what each level costs and what it changes, measured.
#
#   bash scripts/power.sh [--boards "microbit lm3s6965"] [--clip NAME=BVH] [--write]
#
# Encodes a CMU motion onto the 16-servo upper-body figure (assets/rigs/cmu_upper_body.toml,
# 50 Hz) with every codec at 0.5°, then for each codec and level 0–4:
#  - runs the firmware's servo mode with the level (scripts/firmware.sh run --servo pwm
#    --power L --icount --figure the rig) on each board: instructions per tick (all of it: the
#    sampler, the limiter and the output) and the PWM output's share, so per second of show =
#    per tick × 50;
#  - `mocap target levels` on the host: the servos' difference from level 0 (max and RMS degrees
#    of travel, max pulse µs).
# Prints a Markdown table; --write puts it in BENCHMARKS.md between <!-- bench:power --> markers.
# Takes about 15 minutes on 2 cores (30 firmware builds).
set -euo pipefail
# shellcheck source=scripts/toolchain.sh
source "$(dirname "${BASH_SOURCE[0]}")/toolchain.sh"
cd "$MOCAP_REPO_ROOT"
corpus="${MOCAP_CORPUS:-../shared/data}"

boards="microbit lm3s6965"
clip_name="05_04"
clip_src="$corpus/cmu/05_04.bvh"
write=""
while [ "$#" -gt 0 ]; do
    case "$1" in
        --boards) [ "$#" -ge 2 ] || { echo "power.sh: --boards needs a list" >&2; exit 2; }; boards="$2"; shift 2 ;;
        --clip) [ "$#" -ge 2 ] || { echo "power.sh: --clip needs NAME=BVH" >&2; exit 2; }
            clip_name="${2%%=*}"; clip_src="${2#*=}"; shift 2 ;;
        --write) write=1; shift ;;
        -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
        *) echo "power.sh: unknown argument '$1'" >&2; exit 2 ;;
    esac
done
[ -r "$clip_src" ] || { echo "power.sh: cannot read $clip_src (set MOCAP_CORPUS or give --clip NAME=BVH)" >&2; exit 2; }

rig=assets/rigs/cmu_upper_body.toml
cargo build --release -q -p mocap-cli
mocap="${CARGO_TARGET_DIR:-target}/release/mocap"
out=target/power
mkdir -p "$out"
table="$out/table.md"

{
    echo "Command: \`bash scripts/power.sh\` ($clip_name on \`$rig\`, 16 servos at 50 Hz, every codec at 0.5°;"
    echo "instructions per tick = sampler + limiter + PWM output, \`scripts/firmware.sh run --servo pwm --power L --icount\`;"
    echo "error = \`mocap target levels\`, the servos against level 0)."
    echo
    printf '| codec | clip bytes | level | poses/s |'
    for b in $boards; do printf ' %s instr/tick | %s instr/s of show |' "$b" "$b"; done
    echo ' max ° vs level 0 | RMS ° | max pulse µs |'
    printf '|---|---|---|---|'
    for _ in $boards; do printf -- '---|---|'; done
    echo '---|---|---|'
} >"$table"

for codec in index pca-spline predictive; do
    clip="$out/$clip_name-$codec.mcb"
    "$mocap" encode "$clip_src" --rig "$rig" --codec "$codec" --max-error 0.5deg -o "$clip" >/dev/null
    bytes=$(stat -c %s "$clip")
    levels="$("$mocap" target levels "$clip" | tail -n +2)"
    for level in 0 1 2 3 4; do
        row="$(awk -v l="$level" '$1 == l' <<<"$levels")"
        read -r _ per_s max_deg rms_deg max_pulse <<<"$row"
        line="| $codec | $bytes | $level | $per_s |"
        for b in $boards; do
            uart="$(bash scripts/firmware.sh run --board "$b" --clip "$clip" --servo pwm --figure "$rig" \
                --power "$level" --icount)"
            per_tick="$(sed -n 's/^# servo_ticks=[0-9]* per_tick=\([0-9]*\).*/\1/p' <<<"$uart")"
            [ -n "$per_tick" ] || { echo "power.sh: no servo_ticks line from $b ($codec, level $level)" >&2; exit 1; }
            line="$line $per_tick | $((per_tick * 50)) |"
            echo "power.sh: $codec level $level on $b: $per_tick instructions per tick" >&2
        done
        echo "$line $max_deg | $rms_deg | $max_pulse |" >>"$table"
    done
done

cat "$table"
if [ -n "$write" ]; then
    # shellcheck source=scripts/bench_splice.sh
    source scripts/bench_splice.sh
    splice_benchmarks power "$table"
fi
