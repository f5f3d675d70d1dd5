#!/usr/bin/env bash
# The main job on the clip the project ships: encode the procedural
# animatronic demo (assets/animatronic_demo.bvh) for an MCU at 1°, show what
# is inside, measure it, then play it on an emulated Cortex-M3 in QEMU and
# check the firmware's output against the host decoder.
set -euo pipefail
# shellcheck source=scripts/toolchain.sh
source "$(dirname "${BASH_SOURCE[0]}")/toolchain.sh"
cd "$MOCAP_REPO_ROOT"
mocap_explain_failure demo.sh
mocap_toolchain_setup >&2

cargo build --release -q -p mocap-cli
mocap=target/release/mocap
out=target/demo
mkdir -p "$out"
"$mocap" encode --target mcu --codec index --max-error 1deg assets/animatronic_demo.bvh -o "$out/demo.mcb"
"$mocap" info "$out/demo.mcb"
"$mocap" eval assets/animatronic_demo.bvh "$out/demo.mcb"
"$mocap" decode "$out/demo.mcb" -o "$out/demo_decoded.bvh"
"$mocap" decode --text "$out/demo.mcb" -o "$out/host.txt"
echo "playing on Cortex-M3 (QEMU lm3s6965evb)…" >&2
bash scripts/firmware.sh run --board lm3s6965 --clip "$out/demo.mcb" --icount >"$out/uart.txt"
grep '^#' "$out/uart.txt"
if grep -v '^#' "$out/uart.txt" | cmp -s - "$out/host.txt"; then
    echo "firmware output identical to the host decoder ($(grep -vc '^#' "$out/uart.txt") frames)"
else
    echo "firmware output DIFFERS from the host decoder" >&2
    exit 1
fi

# The same clip as an animatronic show: the demo rig's 12 servos coded in servo space, played by
# the host into Pololu Maestro commands and by the firmware's servo loop on the Cortex-M3, both
# held to the figure's hard limits (the demo rig; the firmware's default MOCAP_FIGURE); the two
# byte streams must agree.
mocap_logged "$out/encode_servo.log" "$mocap" encode assets/animatronic_demo.bvh \
    --rig assets/rigs/animatronic_demo.toml --max-error 0.5deg -o "$out/demo_servo.mcb"
"$mocap" play "$out/demo_servo.mcb" --rig assets/rigs/animatronic_demo.toml --protocol maestro \
    --output "$out/host.maestro" --fast
echo "playing the servo clip on Cortex-M3 (QEMU, Maestro output)…" >&2
bash scripts/firmware.sh run --board lm3s6965 --clip "$out/demo_servo.mcb" --servo maestro --icount \
    >"$out/uart_servo.txt"
grep -E '^# (figure|hard_clamps|servo_ticks)' "$out/uart_servo.txt"
# Both as one flat hex string (od is in coreutils).
fw_hex=$(grep '^m' "$out/uart_servo.txt" | sed 's/^m//' | tr -d ' \n')
host_hex=$(od -An -v -tx1 "$out/host.maestro" | tr -d ' \n')
if [ -n "$fw_hex" ] && [ "$fw_hex" = "$host_hex" ]; then
    echo "firmware Maestro bytes identical to mocap play ($(grep -c '^m' "$out/uart_servo.txt") ticks)"
else
    echo "firmware Maestro bytes DIFFER from mocap play" >&2
    exit 1
fi

# The demo take as a show: four clips cut from it (one per codec choice, two looping), a cue list
# with a sound-module command and GPIO events, triggers; run by a command script on the host and,
# from flash, by the firmware's show mode on the Cortex-M3 with the same commands over its UART.
"$mocap" show build assets/shows/demo.toml -o "$out/demo_show.mcb"
"$mocap" info "$out/demo_show.mcb" | grep -E '^(show|servo show|clip|cue list|trigger)'
"$mocap" play "$out/demo_show.mcb" --cues assets/shows/demo_cues.txt --rig assets/rigs/animatronic_demo.toml \
    --protocol maestro --output "$out/show_host.maestro" --fast 2>"$out/show_host.log"
"$mocap" send "$out/demo_show.mcb" --cues assets/shows/demo_cues.txt --output "$out/show_cmds.bin" --fast
echo "playing the show on Cortex-M3 (QEMU, show mode, commands over the UART)…" >&2
bash scripts/firmware.sh run --board lm3s6965 --clip "$out/demo_show.mcb" --servo maestro \
    --input "$out/show_cmds.bin" --stream-timeout 0 --icount >"$out/uart_show.txt"
grep -E '^# (mode=show|event|show_ticks|blend_ticks|plain_ticks)' "$out/uart_show.txt"
fw_hex=$(grep '^m' "$out/uart_show.txt" | sed 's/^m//' | tr -d ' \n')
host_hex=$(od -An -v -tx1 "$out/show_host.maestro" | tr -d ' \n')
if [ -n "$fw_hex" ] && [ "$fw_hex" = "$host_hex" ] \
    && diff <(grep '^# event' "$out/uart_show.txt") <(grep '^# event' "$out/show_host.log") >/dev/null; then
    echo "firmware show: Maestro bytes and events identical to mocap play ($(grep -c '^m' "$out/uart_show.txt") ticks)"
else
    echo "firmware show DIFFERS from mocap play" >&2
    exit 1
fi
